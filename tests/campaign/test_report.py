"""fdikit.campaign.report: the self-contained HTML page, escaping, example traces, atomic writes."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from urllib.parse import quote

import numpy as np
import pytest

from fdikit.campaign.report import pick_examples, trace_file_name, write_report
from fdikit.campaign.schema import table_from_rows
from fdikit.errors import DataError

NAN = math.nan
LEVELS = [0.5, 1.0, 2.0]
#: Names that need escaping in HTML and sanitising in file names.
ODD_DESIGN = '<b>bank&"x"</b>'
ODD_EVALUATOR = "cusum/2 'a'"


def synthetic_rows(seed: int = 0, runs: int = 24, designs=("bank", ODD_DESIGN),
                   evaluators=("threshold", ODD_EVALUATOR)):
    """A synthetic results table: faults a, b, c and fault-free runs, random detections and false alarms."""
    rng = np.random.default_rng(seed)
    rows = []
    for d_i, design in enumerate(designs):
        for evaluator in evaluators:
            for run in range(runs):
                fault = ("none", "a_sensor", "b_sensor", "c_actuator")[run % 4]
                faulty = fault != "none"
                det = faulty and rng.random() < 0.9 - 0.2 * d_i
                delay = float(rng.gamma(2.0, 0.5 + d_i)) if det else NAN
                fa = int(rng.poisson(0.4))
                isolated = (fault if rng.random() < 0.85 else "unknown") if det else ("a_sensor" if fa else "none")
                if faulty and not det:
                    isolated = "none"
                sweep_delay = [delay * s if det else NAN for s in LEVELS] if faulty else [NAN] * 3
                rows.append(dict(
                    run=run, chunk=run // 8, plant="linear", fault=fault, kind="bias" if faulty else "none",
                    size=1.0 if faulty else NAN, onset=5.0 if faulty else NAN, seed=run, design=design,
                    evaluator=evaluator, detected=det, missed=faulty and not det, detection_delay=delay,
                    isolated=isolated, isolation_correct=(isolated == fault) if faulty else None,
                    isolation_delay=delay + 0.2 if det and isolated == fault else NAN,
                    correct_fraction=0.9 if det else NAN, false_alarms=fa,
                    fault_free_hours=(10.0 if not faulty else 5.0) / 3600,
                    sweep_delay=sweep_delay, sweep_false_alarms=[int(rng.poisson(8 / s ** 2)) for s in LEVELS],
                    metrics="{}"))
    return rows


def write_campaign(folder: Path, rows=None, name: str = "synthetic <demo> & co") -> Path:
    """A results folder (campaign.json and runs/chunk-*.parquet) holding ``rows``."""
    import pyarrow.parquet as pq

    rows = synthetic_rows() if rows is None else rows
    (folder / "runs").mkdir(parents=True)
    for chunk in sorted({r["chunk"] for r in rows}):
        part = [r for r in rows if r["chunk"] == chunk]
        pq.write_table(table_from_rows(part), folder / "runs" / f"chunk-{chunk:06d}.parquet")
    meta = {"format": 1, "name": name, "fingerprint": "abc123", "fdikit": "0.0-test", "spec": {},
            "levels": LEVELS, "runs": len({r["run"] for r in rows}), "chunks": 3, "duration": 12.5,
            "designs": sorted({r["design"] for r in rows}), "evaluators": sorted({r["evaluator"] for r in rows})}
    (folder / "campaign.json").write_text(json.dumps(meta), encoding="utf-8")
    return folder


def fake_replay(calls: list | None = None):
    """A replay callable: a tiny real Trace, Residuals and a ThresholdEvaluator's Diagnosis."""
    from fdikit.decision import ThresholdEvaluator
    from fdikit.residuals import Residuals
    from fdikit.trace import Trace

    def replay(run, design, evaluator):
        if calls is not None:
            calls.append((run, design, evaluator))
        t = np.arange(200) * 0.05
        fault = np.where(t >= 5.0, "a_sensor", "none") if run % 4 else np.full(t.size, "none")
        rng = np.random.default_rng(run)
        r = 0.3 * rng.standard_normal((t.size, 2))
        r[:, 0] += 2.0 * (fault != "none")
        trace = Trace(t=t, u=np.zeros((t.size, 1)), y=r.copy(), controls=["u"], outputs=["y1", "y2"], fault=fault)
        res = Residuals(t, r, ("r_a", "r_b"), ("a_sensor", "b_sensor"))
        return trace, res, ThresholdEvaluator(thresholds=[1.0, 1.0]).run(res)

    return replay


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    return write_campaign(tmp_path_factory.mktemp("campaign"))


@pytest.fixture(scope="module")
def page_without_replay(campaign):
    return write_report(campaign)


def test_page_is_written_and_self_contained(page_without_replay, campaign):
    assert page_without_replay == campaign / "report.html"
    text = page_without_replay.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")
    assert not re.search(r"""(?:src|href)\s*=\s*["']?\s*(?:https?:)?//""", text, re.I)
    assert "<script" not in text.lower() and "@import" not in text and "url(" not in text
    srcs = re.findall(r"""<img[^>]*\ssrc="([^"]*)\"""", text)
    assert len(srcs) == 3 and all(s.startswith("data:image/png;base64,") for s in srcs)
    assert "Example traces were not requested" in text
    assert not (campaign / "report-traces").exists()


def test_page_shows_the_summary_and_tables(page_without_replay):
    text = page_without_replay.read_text(encoding="utf-8")
    for needle in ("abc123", "0.0-test", "12.5 s", "Comparison of the designs", "Detection rate per fault",
                   "Trade-off over the threshold sweep", "Confusion matrices", "False alarms", "c_actuator",
                   "Clopper–Pearson", "Garwood"):
        assert needle in text, needle


def test_names_are_escaped(page_without_replay):
    text = page_without_replay.read_text(encoding="utf-8")
    assert ODD_DESIGN not in text and "<demo>" not in text
    assert "&lt;b&gt;bank&amp;&quot;x&quot;&lt;/b&gt;" in text
    assert "synthetic &lt;demo&gt; &amp; co" in text
    assert "cusum/2 &#x27;a&#x27;" in text


def test_example_traces_are_drawn_and_linked(tmp_path):
    folder = write_campaign(tmp_path / "c", synthetic_rows(designs=(ODD_DESIGN,)))
    calls = []
    page = write_report(folder, replay=fake_replay(calls), examples=2)
    text = page.read_text(encoding="utf-8")
    files = sorted((folder / "report-traces").iterdir())
    assert len(files) == len(calls) == 4  # two runs for each of the two pairs
    assert all(f.read_bytes()[1:4] == b"PNG" for f in files)
    hrefs = re.findall(r'<a href="([^"]*)">', text)
    assert sorted(hrefs) == sorted("report-traces/" + quote(f.name) for f in files)
    for run, design, evaluator in calls:
        assert (folder / "report-traces" / trace_file_name(run, design, evaluator)).is_file()
    assert all(not any(c in f.name for c in "<>&\"'/ ") for f in files)
    assert "Example traces were not requested" not in text
    assert not [p for p in folder.rglob("*") if p.name.endswith(".tmp")]  # atomic writes leave no temp files


def test_examples_pick_a_miss_a_false_alarm_and_the_slowest():
    import pandas as pd

    df = table_from_rows(synthetic_rows(seed=4)).to_pandas()
    picks = pick_examples(df, 3)
    assert picks == pick_examples(df.sample(frac=1.0, random_state=0), 3)  # depends on the rows, not their order
    for p in picks:
        g = df[(df["design"] == p["design"]) & (df["evaluator"] == p["evaluator"])]
        if p["reason"] == "missed detection":
            assert p["run"] == g.loc[g["missed"], "run"].min()
        elif p["reason"] == "slowest detection":
            assert p["detection_delay"] == g["detection_delay"].max()
        else:
            assert p["false_alarms"] == g.loc[g["fault"] == "none", "false_alarms"].max() > 0
    assert pick_examples(df, 0) == [] and pick_examples(pd.DataFrame(columns=df.columns), 2) == []


def test_a_failing_replay_is_reported_on_the_page(tmp_path):
    folder = write_campaign(tmp_path / "c", synthetic_rows(designs=("bank",), evaluators=("threshold",)))

    def broken(run, design, evaluator):
        raise RuntimeError(f"cannot replay <{run}>")

    text = write_report(folder, replay=broken, examples=1).read_text(encoding="utf-8")
    assert "replay failed (RuntimeError: cannot replay &lt;" in text


def test_custom_output_path_links_relative_to_it(tmp_path):
    folder = write_campaign(tmp_path / "c", synthetic_rows(designs=("bank",), evaluators=("threshold",)))
    out = tmp_path / "pages" / "r.html"
    text = write_report(folder, out=out, replay=fake_replay(), examples=1).read_text(encoding="utf-8")
    hrefs = re.findall(r'<a href="([^"]*)">', text)
    assert hrefs and all(h.startswith("../c/report-traces/") for h in hrefs)


def test_progress_bar_and_no_temp_files(tmp_path):
    folder = write_campaign(tmp_path / "c", synthetic_rows(designs=("bank",), evaluators=("threshold",)))
    write_report(folder, progress=True)
    assert sorted(p.name for p in folder.iterdir()) == ["campaign.json", "report.html", "runs"]


def test_missing_folder_parts(tmp_path):
    with pytest.raises(DataError, match="campaign.json"):
        write_report(tmp_path)
    (tmp_path / "campaign.json").write_text(json.dumps({"levels": LEVELS}))
    with pytest.raises(DataError, match="no Parquet chunks"):
        write_report(tmp_path)
    (tmp_path / "campaign.json").write_text("{not json")
    with pytest.raises(DataError, match="cannot read"):
        write_report(tmp_path)


def test_study_figures_section(tmp_path):
    rows = synthetic_rows(runs=8)
    for k, row in enumerate(rows):
        row["metrics"] = json.dumps({"rmse <m>": float(k), "kept": float(k % 2)})
    page = write_report(write_campaign(tmp_path / "c", rows)).read_text(encoding="utf-8")
    assert "<h2>Study figures</h2>" in page and "rmse &lt;m&gt;" in page
    assert "This study stores no figures" not in page


def test_metric_summary_against_a_loop():
    import pandas as pd

    from fdikit.campaign.stats import metric_summary

    rng = np.random.default_rng(4)
    rows = synthetic_rows(runs=12)
    for row in rows:
        row["metrics"] = json.dumps({"e": float(rng.normal()), **({"nan": math.nan} if row["run"] % 3 else {})})
    table = pd.DataFrame(rows)
    got = metric_summary(table)
    for r in got.itertuples(index=False):
        sel = table[(table.design == r.design) & (table.evaluator == r.evaluator) & (table.fault == r.fault)]
        vals = [json.loads(m)[r.metric] for m in sel.metrics if r.metric in json.loads(m)]
        finite = [v for v in vals if math.isfinite(v)]
        assert r.runs == len(finite)
        if finite:
            assert r.mean == pytest.approx(sum(finite) / len(finite), rel=1e-12)
            assert (r.min, r.max) == (min(finite), max(finite))
        else:
            assert math.isnan(r.mean)
    with pytest.raises(DataError, match="is not a JSON object of numbers"):
        metric_summary(pd.DataFrame({"design": ["a"], "evaluator": ["e"], "fault": ["none"], "metrics": ["[1"]}))
