"""LIP isolation on the nonlinear JSBSim B747 (Hallouzi 2008, §4.4.2): one flight, the logic, Table 4.8 reduced."""

import numpy as np
import pytest

from fdikit.errors import ParameterError
from fdikit.studies.hallouzi2008.b747_lip import _persistent, fly_lip, lip_setup
from fdikit.studies.hallouzi2008.table_4_8 import (
    THESIS_TABLE_4_8,
    LipRow,
    Table48,
    lock_positions,
)


@pytest.fixture(scope="module")
def setup():
    # a shorter calibration flight than the command's 300 s: Q from 60 s of turbulence (6000 one-step errors
    # for a 10 × 10 covariance) is within a few per cent of the long one
    return lip_setup(calibration_seconds=60.0)


def test_persistence_declares_a_signature_held_k_of_n_samples():
    raw = np.array(["none", "elevator", "elevator", "none", "elevator", "aileron", "aileron", "aileron", "none"])
    assert _persistent(raw, 1, 1).tolist() == raw.tolist()
    assert _persistent(raw, 2, 3).tolist() == ["none", "none", "elevator", "elevator", "elevator", "none",
                                               "aileron", "aileron", "aileron"]
    assert _persistent(raw, 3, 3).tolist() == ["none"] * 7 + ["aileron", "none"]
    assert _persistent(np.array(["none"] * 4), 2, 3).tolist() == ["none"] * 4


def test_sweep_sizes_are_the_thesis_run_counts():
    assert {s: len(lock_positions(s)) for s in THESIS_TABLE_4_8} == {s: v["runs"] for s, v in THESIS_TABLE_4_8.items()}


def test_lip_travels_to_the_lock_and_a_large_elevator_lock_is_isolated(setup):
    run = fly_lip(setup, "elevator", -18.0, seed=5, duration=26.0)
    k = np.searchsorted(run.t, 20.0)
    # 37 deg/s (App. A): about −1 deg to −18 deg in 0.46 s, then the 0.05-s lag closes the rest
    # (e^(−0.54/0.05) ≈ 2e-5 of the gap left after 1 s)
    assert run.positions[k + 100] == pytest.approx(-18.0, abs=1e-3)
    assert np.min(np.diff(run.positions)) / 0.01 == pytest.approx(-37.0, rel=1e-9)
    assert run.false_alarms == 0
    assert run.outcome == "correct"
    assert run.first[1] < 2.0
    groups = run.mu[:, [2, 4, 5]].sum(axis=1)  # the elevator models of model set II
    assert groups[-1] > 0.9


def test_outcome_rules():
    t = np.arange(0.0, 1.0, 0.01)
    from fdikit.studies.hallouzi2008.b747_lip import LipRun

    def run(first, fa):
        return LipRun(t, np.zeros((t.size, 8)), np.full(t.size, "none"), "rudder", 5.0, first, fa, t, t)

    assert run(("rudder", 1.0), 0).outcome == "correct"
    assert run(("aileron", 1.0), 0).outcome == "incorrect"
    assert run((None, np.nan), 0).outcome == "missed"
    assert run(("rudder", 1.0), 1).outcome == "false alarm"


def test_table_summary_and_markdown():
    rows = (LipRow("rudder", 0.0, 1, "missed", None, np.nan, "none", 0.0),
            LipRow("rudder", 5.0, 2, "correct", "rudder", 3.0, "rudder", 0.0),
            LipRow("rudder", 10.0, 3, "correct", "rudder", 1.0, "rudder", 0.0),
            LipRow("rudder", 15.0, 4, "incorrect", "aileron", 2.0, "aileron", 0.0))
    summ = Table48(rows, {}).summary()["rudder"]
    assert summ == {"correct": 50.0, "incorrect": 25.0, "missed": 25.0, "false alarm": 0.0, "delay": 2.0, "runs": 4}
    assert "75.2 %" in Table48(rows, {}).markdown()  # the thesis's rudder figure beside ours


def test_bad_arguments(setup):
    with pytest.raises(ParameterError, match="surface"):
        fly_lip(setup, "spoiler", 1.0)
    with pytest.raises(ParameterError, match="lock"):
        fly_lip(setup, "elevator", 30.0)
    with pytest.raises(ParameterError, match="noise"):
        lip_setup(noise="datasheet")


def test_reduced_table_4_8_is_within_sampling_tolerance_of_the_full_sweep(setup):
    """Every 10 deg (15 runs, the full sweep's own seeds) against the recorded 243-run sweep.

    A reduced sweep is a sample of the full one's lock positions: its share of correct runs is within
    three binomial standard deviations of the full share (plus one run, for the rounding of a small n),
    and its mean delay within three standard errors of the full mean (the full runs' delay spread).
    """
    from fdikit.studies.hallouzi2008.table_4_8 import FDIKIT_TABLE_4_8, table_4_8

    summary = table_4_8(setup, step=10.0).summary()
    for surface, full in FDIKIT_TABLE_4_8.items():
        got, n = summary[surface], summary[surface]["runs"]
        assert n == len(lock_positions(surface, 10.0))
        p = full["correct"] / 100
        assert abs(got["correct"] / 100 - p) <= 3 * np.sqrt(p * (1 - p) / n) + 1 / n, (surface, got)
        n_correct = round(got["correct"] * n / 100)
        assert abs(got["delay"] - full["delay"]) <= 3 * full["delay_std"] / np.sqrt(n_correct), (surface, got)
