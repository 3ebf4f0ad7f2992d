"""Signature-table isolation (fdikit.decision.signature) and its use by the per-residual evaluators."""

import numpy as np
import pandas as pd
import pytest

from fdikit import FaultModel
from fdikit.decision import CusumEvaluator, GlrEvaluator, SprtEvaluator, ThresholdEvaluator
from fdikit.decision.signature import SignatureTable, signature_isolation
from fdikit.design import observer_generator
from fdikit.errors import DataError, ParameterError
from fdikit.faults import Bias, FaultScenario
from fdikit.metrics import score
from fdikit.residuals import Residuals
from fdikit.simulate import simulate

NOISE = 0.01  # measurement noise std [output units]
ONSET = 20.0


@pytest.fixture(scope="module")
def coupled():
    """Actuator u0 drives both states (Bu column [1, 1]), u1 only the second: with one observer residual per
    output, tied to u0_actuator (y0) and u1_actuator (y1), a u0 fault fires both residual groups."""
    m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.array([[1.0, 0.0], [1.0, 1.0]]),
                   outputs=["y0", "y1"], controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
    gen = observer_generator(m, np.diag([4.0, 5.0]), isolates=["u0_actuator", "u1_actuator"])  # poles −5, −7
    table = SignatureTable.from_generator(gen, m)

    def run(faults, seed):
        trace = simulate(m, FaultScenario(faults), duration=60.0, dt=0.05, measurement_noise_std=NOISE, rng=seed)
        return trace, gen.run(trace)

    return m, gen, table, run


def test_structure_of_the_coupled_design(coupled):
    _, _, table, _ = coupled
    # u0 reaches x0 and x1 (B column [1, 1]) and both outputs; u1 reaches only x1 -> y1.
    assert table.signature("u0_actuator") == ("u0_actuator", "u1_actuator")
    assert table.signature("u1_actuator") == ("u1_actuator",)
    assert table.indistinguishable == () and table.undetectable == ()
    assert table.isolable == ("u0_actuator", "u1_actuator")


def test_two_group_fault_is_named_by_the_signature_table(coupled):
    """Steady state of the residual under a unit u0 bias: e' = (A − LC) e + B f gives r = (1/5, 1/7) = (0.2, 0.143),
    against thresholds ≈ σ Φ⁻¹(1 − α/4) with σ ≈ NOISE: at 1 false alarm/h and dt = 0.05, α = 1.4e−5 and the
    threshold is ≈ 4.7 σ = 0.047, so from 1 s after the onset (transient e^{−5t} below 1 %) both residuals
    exceed by more than 9 σ on every sample: a miss has probability < 1e−18 per sample."""
    _, _, table, run = coupled
    _, healthy = run([], 1)
    trace, faulty = run([Bias("u0", 1.0, onset=ONSET, location="actuator")], 2)
    plain = ThresholdEvaluator().fit(healthy, false_alarms_per_hour=1.0)
    signed = ThresholdEvaluator(signatures=table).fit(healthy, false_alarms_per_hour=1.0)
    settled = trace.t >= ONSET + 1.0
    d_plain, d_signed = plain.run(faulty), signed.run(faulty)
    assert d_plain.fired[settled].all() and d_signed.fired[settled].all()
    assert set(d_plain.isolated[settled]) == {"unknown"}  # the single-residual rule: two faults' residuals fired
    assert set(d_signed.isolated[settled]) == {"u0_actuator"}
    s_plain, s_signed = score(trace, d_plain), score(trace, d_signed)
    assert s_plain.isolated == "unknown" and s_plain.isolation_correct is False and s_plain.isolation_delay is None
    assert s_signed.isolation_correct is True and s_signed.isolation_delay <= 1.0
    # the one-group fault is named by both logics
    trace1, faulty1 = run([Bias("u1", 1.0, onset=ONSET, location="actuator")], 3)
    assert set(signed.run(faulty1).isolated[trace1.t >= ONSET + 1.0]) == {"u1_actuator"}


def _stepped(ev, res):
    ev.reset()
    out = [ev.step(res.r[k], valid=bool(res.valid[k])).fault for k in range(len(res.t))]
    ev.reset()
    return np.array(out)


def test_batch_and_step_name_the_same_fault(coupled):
    """Every per-residual evaluator with signatures=: run and step give identical labels, sample for sample, through
    a gap (NaN rows) and a recovering (invalid) stretch."""
    _, _, table, run = coupled
    _, healthy = run([], 4)
    _, faulty = run([Bias("u0", 0.3, onset=ONSET, location="actuator"),
                     Bias("u1", 0.3, onset=40.0, location="actuator")], 5)
    r = faulty.r.copy()
    r[300:310] = np.nan
    valid = faulty.valid.copy()
    valid[310:320] = False
    res = Residuals(faulty.t, r, faulty.names, faulty.isolates, valid)
    evaluators = [
        ThresholdEvaluator(persistence=(2, 3), signatures=table).fit(healthy, false_alarms_per_hour=10.0),
        ThresholdEvaluator(signatures=SignatureTable(table, match="partial")).fit(healthy, false_alarm_prob=1e-3),
        CusumEvaluator(signatures=table).fit(healthy, arl0=1e4, shift=0.05),
        GlrEvaluator(window=10, signatures=table).fit(healthy, false_alarm_prob=1e-4),
        SprtEvaluator(shift=0.05, signatures=table).fit(healthy),
    ]
    for ev in evaluators:
        batch = ev.run(res).isolated
        assert np.array_equal(batch, _stepped(ev, res)), ev
        assert "u0_actuator" in set(batch)  # the table is used: u0 fires both groups


def test_exact_and_partial_matching():
    tab = SignatureTable({"fa": ["g1", "g2"], "fb": ["g2", "g3"], "fc": ["g1"]})
    part = SignatureTable(tab, match="partial")
    cases = {  # fired groups -> (exact, partial)
        (): ("none", "none"),
        ("g1", "g2"): ("fa", "fa"),
        ("g1",): ("fc", "fc"),  # an exact match wins over the partial pattern of fa
        ("g3",): ("unknown", "fb"),  # part of fb only
        ("g2",): ("unknown", "unknown"),  # part of fa and of fb
        ("g1", "g3"): ("unknown", "unknown"),  # no fault's pattern
        ("g1", "g2", "g3"): ("unknown", "unknown"),
    }
    for fired, (e, p) in cases.items():
        assert (tab.label(fired), part.label(fired)) == (e, p), fired


def test_indistinguishable_faults_are_never_named():
    tab = SignatureTable({"fa": ["g1"], "fb": ["g1"], "fc": ["g2"], "fd": []}, match="partial")
    assert tab.indistinguishable == (("fa", "fb"),)
    assert tab.undetectable == ("fd",)
    assert tab.isolable == ("fc",)
    fired = np.array([[True, False], [False, True], [True, True]])
    assert signature_isolation(fired, tab, ("g1", "g2")).tolist() == ["unknown", "fc", "unknown"]


def test_table_forms_agree():
    df = pd.DataFrame([[True, True], [False, True]], index=["fa", "fb"], columns=["ra", "rb"])
    fired = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=bool)
    expected = ["none", "unknown", "fa", "fb"]
    assert signature_isolation(fired, df, ("ra", "rb")).tolist() == expected
    assert signature_isolation(fired, {"fa": ["ra", "rb"], "fb": "rb"}, ("ra", "rb")).tolist() == expected
    # groups found through the residuals' tied faults, or through members=
    assert signature_isolation(fired, {"fa": ["x", "y"], "fb": ["y"]}, ("ra", "rb"), ("x", "y")).tolist() == expected
    members = SignatureTable({"fa": ["G1", "G2"], "fb": ["G2"]}, members={"G1": ["ra"], "G2": ["rb"]})
    assert members.isolate(fired, ("ra", "rb")).tolist() == expected
    assert SignatureTable(df).to_pandas().equals(df.rename_axis(index="fault", columns="residual"))


def test_bad_tables_are_refused():
    with pytest.raises(ParameterError, match="match"):
        SignatureTable({"fa": ["g"]}, match="closest")
    with pytest.raises(ParameterError, match="boolean"):
        SignatureTable(pd.DataFrame([[1, 0]], index=["fa"], columns=["a", "b"]))
    with pytest.raises(ParameterError, match="no faults"):
        SignatureTable({})
    with pytest.raises(ParameterError, match="twice"):
        SignatureTable({"fa": ["g", "g"]})
    with pytest.raises(ParameterError, match="not in the table"):
        SignatureTable({"fa": ["g"]}, members={"h": ["r"]})
    with pytest.raises(ParameterError, match="mapping"):
        SignatureTable([("fa", "g")])
    tab = SignatureTable({"fa": ["ra"], "fb": ["rb"]})
    with pytest.raises(DataError, match="no group"):
        tab.resolve(("ra", "rb", "rc"))
    with pytest.raises(DataError, match="none of the residuals"):
        tab.resolve(("ra",))
    with pytest.raises(ParameterError, match="not in the signature table"):
        tab.signature("fc")
