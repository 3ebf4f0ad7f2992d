"""fdikit.campaign.stats: exact rates and intervals from synthetic result tables with known counts."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import beta, binomtest, chi2

from fdikit.campaign.schema import table_from_rows
from fdikit.campaign.stats import REQUIRED_COLUMNS, campaign_statistics, clopper_pearson
from fdikit.errors import DataError, ParameterError
from fdikit.metrics import Score, confusion_matrix

NAN = math.nan
LEVELS = (0.5, 1.0, 2.0)


def row(run, fault="none", design="bank", evaluator="threshold", detected=False, delay=NAN, isolated=None,
        iso_delay=NAN, false_alarms=0, hours=0.01, sweep_delay=None, sweep_fa=None):
    faulty = fault != "none"
    if isolated is None:
        isolated = fault if (faulty and detected) else "none"
    return dict(run=run, chunk=run // 10, plant="p", fault=fault, kind="bias" if faulty else "none",
                size=1.0 if faulty else NAN, onset=10.0 if faulty else NAN, seed=run, design=design,
                evaluator=evaluator, detected=detected, missed=faulty and not detected,
                detection_delay=delay if detected else NAN, isolated=isolated,
                isolation_correct=(isolated == fault and detected) if faulty else None, isolation_delay=iso_delay,
                correct_fraction=NAN, false_alarms=false_alarms, fault_free_hours=hours,
                sweep_delay=list(sweep_delay or [NAN] * len(LEVELS)),
                sweep_false_alarms=list(sweep_fa or [0] * len(LEVELS)), metrics="{}")


def known_rows():
    """Fault a: 10 runs, 7 detected (6 isolated right, 1 as b); fault b: 10 runs, none detected; 5 fault-free."""
    rows = []
    delays = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 2.0]
    for k in range(10):
        det = k < 7
        rows.append(row(k, "a", detected=det, delay=delays[k] if det else NAN, isolated=("b" if k == 6 else None),
                        iso_delay=delays[k] + 0.1 if det and k != 6 else NAN, false_alarms=1 if k == 0 else 0,
                        sweep_delay=[0.05 * (k + 1), delays[k] if det else NAN, NAN],
                        sweep_fa=[2, 1 if k == 0 else 0, 0]))
    for k in range(10, 20):
        rows.append(row(k, "b", sweep_delay=[0.5, NAN, NAN] if k < 13 else None, sweep_fa=[1, 0, 0]))
    for k, fa in zip(range(20, 25), (3, 1, 0, 0, 0)):
        rows.append(row(k, "none", false_alarms=fa, isolated="a" if fa else "none", hours=0.2,
                        sweep_fa=[fa + 4, fa, 0]))
    return rows


@pytest.fixture(scope="module")
def known():
    return campaign_statistics(table_from_rows(known_rows()), LEVELS)


def test_detection_counts_and_rates(known):
    d = known.detection.set_index("fault")
    a, b = d.loc["a"], d.loc["b"]
    assert (a["runs"], a["detected"], a["missed"], a["detection_rate"]) == (10, 7, 3, 0.7)
    assert (b["runs"], b["detected"], b["missed"], b["detection_rate"]) == (10, 0, 10, 0.0)
    delays = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 2.0])
    assert a["delay_count"] == 7
    assert a["delay_median"] == pytest.approx(0.4)
    assert a["delay_mean"] == pytest.approx(delays.mean())
    assert a["delay_p10"] == pytest.approx(np.percentile(delays, 10))
    assert a["delay_p90"] == pytest.approx(np.percentile(delays, 90))
    assert a["delay_max"] == 2.0
    assert (a["isolated_correct"], a["isolation_rate"]) == (6, 0.6)
    assert a["isolation_delay_count"] == 6 and a["isolation_delay_median"] == pytest.approx(0.35 + 0.1)
    assert b["delay_count"] == 0 and math.isnan(b["delay_median"]) and math.isnan(b["isolation_delay_max"])


def test_clopper_pearson_textbook_values(known):
    b = known.detection.set_index("fault").loc["b"]
    assert (b["detection_low"], round(b["detection_high"], 4)) == (0.0, 0.3085)  # 0 of 10 at 95 %
    assert [round(x, 4) for x in clopper_pearson(10, 10)] == [0.6915, 1.0]
    assert [round(x, 4) for x in clopper_pearson(5, 10)] == [0.1871, 0.8129]
    a = known.detection.set_index("fault").loc["a"]
    assert (a["detection_low"], a["detection_high"]) == pytest.approx(
        (beta.ppf(0.025, 7, 4), beta.ppf(0.975, 8, 3)), rel=1e-12)


@pytest.mark.parametrize("confidence", [0.9, 0.95, 0.99])
def test_clopper_pearson_agrees_with_binomtest_and_beta(confidence):
    a = 1 - confidence
    for n in (1, 2, 7, 30, 101):
        for k in range(n + 1):
            lo, hi = clopper_pearson(k, n, confidence)
            ref = binomtest(k, n).proportion_ci(confidence_level=confidence, method="exact")
            assert (lo, hi) == pytest.approx((ref.low, ref.high), rel=1e-9, abs=1e-12)
            assert lo == (0.0 if k == 0 else pytest.approx(beta.ppf(a / 2, k, n - k + 1), rel=1e-12))
            assert hi == (1.0 if k == n else pytest.approx(beta.ppf(1 - a / 2, k + 1, n - k), rel=1e-12))


def test_clopper_pearson_edge_cases():
    assert all(math.isnan(x) for x in clopper_pearson(0, 0))
    with pytest.raises(ParameterError):
        clopper_pearson(3, 2)
    with pytest.raises(ParameterError):
        clopper_pearson(1, 2, confidence=1.0)


def test_false_alarms_and_garwood(known):
    fa = known.false_alarms.iloc[0]
    assert (fa["fault_free_runs"], fa["runs_with_false_alarm"], fa["false_alarm_run_fraction"]) == (5, 2, 0.4)
    assert (fa["false_alarm_run_low"], fa["false_alarm_run_high"]) == pytest.approx(clopper_pearson(2, 5))
    # 3 + 1 on fault-free runs and 1 before the onset of a faulty run, over 5 × 0.2 h + 20 × 0.01 h.
    assert fa["false_alarms"] == 5 and fa["fault_free_hours"] == pytest.approx(1.2)
    assert fa["false_alarm_rate"] == pytest.approx(5 / 1.2)
    assert fa["false_alarm_rate_low"] == pytest.approx(chi2.ppf(0.025, 10) / 2.4, rel=1e-12)
    assert fa["false_alarm_rate_high"] == pytest.approx(chi2.ppf(0.975, 12) / 2.4, rel=1e-12)


def test_overall_pools_the_faults(known):
    o = known.overall.iloc[0]
    assert (o["runs"], o["detected"], o["detection_rate"], o["isolated_correct"]) == (20, 7, 0.35, 6)
    assert o["false_alarm_rate"] == pytest.approx(5 / 1.2)


def random_rows(seed=1, runs=40):
    rng = np.random.default_rng(seed)
    rows = []
    for design in ("bank", "uio"):
        for evaluator in ("threshold", "cusum"):
            for run in range(runs):
                fault = ("none", "a", "b", "c")[run % 4]
                det = fault != "none" and rng.random() < 0.8
                delay = float(rng.exponential(1.0)) if det else NAN
                isolated = str(rng.choice(["a", "b", "unknown", fault])) if det else None
                fa = int(rng.poisson(0.5))
                iso = isolated if fault != "none" else (str(rng.choice(["a", "b"])) if fa else "none")
                sd = [float(delay * s) if det and rng.random() < 0.9 else NAN for s in LEVELS]
                if fault == "none":
                    sd = [NAN] * len(LEVELS)
                sfa = [int(rng.poisson(4 / s)) for s in LEVELS]
                rows.append(row(run, fault, design, evaluator, det, delay, iso, NAN, fa,
                                hours=float(rng.uniform(0.001, 0.01)), sweep_delay=sd, sweep_fa=sfa))
    return rows


def test_tradeoff_against_a_brute_force_loop():
    rows = random_rows()
    st = campaign_statistics(table_from_rows(rows), LEVELS)
    assert len(st.tradeoff) == 4 * len(LEVELS)
    for r in st.tradeoff.itertuples(index=False):
        j = LEVELS.index(r.level)
        mine = [x for x in rows if x["design"] == r.design and x["evaluator"] == r.evaluator]
        fa = sum(x["sweep_false_alarms"][j] for x in mine)
        hours = sum(x["fault_free_hours"] for x in mine)
        faulty = [x for x in mine if x["fault"] != "none"]
        delays = [x["sweep_delay"][j] for x in faulty if math.isfinite(x["sweep_delay"][j])]
        assert r.false_alarms == fa and r.fault_free_hours == pytest.approx(hours)
        assert r.false_alarm_rate == pytest.approx(fa / hours)
        assert (r.false_alarm_rate_low, r.false_alarm_rate_high) == pytest.approx(
            (chi2.ppf(0.025, 2 * fa) / (2 * hours), chi2.ppf(0.975, 2 * fa + 2) / (2 * hours)))
        assert (r.faulty_runs, r.detected) == (len(faulty), len(delays))
        assert r.detection_rate == pytest.approx(len(delays) / len(faulty))
        assert r.delay_median == pytest.approx(float(np.median(delays)))
        assert r.delay_p90 == pytest.approx(float(np.percentile(delays, 90)))


def test_confusion_matrix_matches_metrics():
    rows = random_rows(seed=2)
    st = campaign_statistics(table_from_rows(rows), LEVELS)
    assert len(st.pairs()) == 4
    for design, evaluator in st.pairs():
        scores = [Score(x["fault"], x["onset"] if x["fault"] != "none" else None, x["detected"],
                        x["detection_delay"] if x["detected"] else None, x["false_alarms"], x["fault_free_hours"],
                        x["missed"], x["isolated"], x["isolation_correct"])
                  for x in rows if x["design"] == design and x["evaluator"] == evaluator]
        pd.testing.assert_frame_equal(st.confusion_matrix(design, evaluator), confusion_matrix(scores),
                                      check_dtype=False)


def test_parquet_dataset_gives_the_same_statistics(tmp_path):
    import pyarrow.parquet as pq

    rows = random_rows(seed=3, runs=20)
    (tmp_path / "runs").mkdir()
    pq.write_table(table_from_rows(rows[:40]), tmp_path / "runs" / "chunk-000000.parquet")
    pq.write_table(table_from_rows(rows[40:]), tmp_path / "runs" / "chunk-000001.parquet")
    a = campaign_statistics(pd.read_parquet(tmp_path / "runs"), LEVELS)
    b = campaign_statistics(table_from_rows(rows), LEVELS)
    for name in ("detection", "overall", "false_alarms", "tradeoff", "confusion"):
        pd.testing.assert_frame_equal(getattr(a, name), getattr(b, name))


def test_zero_fault_free_time_gives_nan_rates():
    rows = [row(0, "a", detected=True, delay=1.0, hours=0.0, sweep_delay=[1.0, 1.0, NAN])]
    st = campaign_statistics(table_from_rows(rows), LEVELS)
    fa = st.false_alarms.iloc[0]
    assert fa["fault_free_runs"] == 0 and math.isnan(fa["false_alarm_run_fraction"])
    assert all(math.isnan(fa[c]) for c in ("false_alarm_rate", "false_alarm_rate_low", "false_alarm_rate_high"))
    assert st.tradeoff["false_alarm_rate"].isna().all()
    assert st.tradeoff["detection_rate"].tolist() == [1.0, 1.0, 0.0]


def test_a_pair_with_only_fault_free_runs_has_an_empty_detection_group():
    rows = [row(0, "none", evaluator="cusum", false_alarms=1, isolated="a"), row(1, "a", detected=True, delay=1.0)]
    st = campaign_statistics(table_from_rows(rows), LEVELS)
    o = st.overall.set_index("evaluator").loc["cusum"]
    assert o["runs"] == 0 and math.isnan(o["detection_rate"]) and math.isnan(o["detection_low"])
    assert list(st.detection["evaluator"]) == ["threshold"]
    assert st.confusion_matrix("bank", "cusum").to_dict() == {"a": {"none": 1}, "none": {"none": 0}}


def test_empty_table():
    st = campaign_statistics(pd.DataFrame(columns=REQUIRED_COLUMNS), LEVELS)
    assert all(len(getattr(st, n)) == 0 for n in ("detection", "overall", "false_alarms", "tradeoff", "confusion"))
    assert st.pairs() == []


def test_missing_columns_are_named():
    df = table_from_rows(known_rows()).to_pandas().drop(columns=["sweep_delay", "false_alarms"])
    with pytest.raises(DataError, match=r"\['false_alarms', 'sweep_delay'\]"):
        campaign_statistics(df, LEVELS)


def test_bad_sweep_lengths_and_levels():
    with pytest.raises(DataError, match="sweep levels"):
        campaign_statistics(table_from_rows(known_rows()), (1.0, 2.0))
    for bad in ([], [1.0, 0.5], [0.0, 1.0], [1.0, math.inf]):
        with pytest.raises(ParameterError):
            campaign_statistics(table_from_rows(known_rows()), bad)
    with pytest.raises(ParameterError):
        campaign_statistics([1, 2], LEVELS)
    with pytest.raises(ParameterError):
        campaign_statistics(table_from_rows(known_rows()), LEVELS, confidence=0.0)
