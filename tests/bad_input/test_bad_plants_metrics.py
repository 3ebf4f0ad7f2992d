"""Bad input for the benchmark plants (fdikit.plants), the PATH monitor (fdikit.studies.path1996) and the metrics."""

from __future__ import annotations

import numpy as np
import pytest
from harness import case, check, ids

from fdikit.diagnosis import Diagnosis
from fdikit.errors import DataError, ParameterError
from fdikit.metrics import confusion_matrix, score, summarize, vaf
from fdikit.plants import (
    SingleTrackParameters,
    b747_longitudinal,
    b747_model_set,
    f16xl_gust,
    get_plant,
    msd,
    msd_matrices,
    path_vehicle_12,
    path_vehicle_14,
    rho_from_speed,
    rounding_intervals,
    single_track,
    single_track_lpv,
    understeer_gradient,
    varrier_lateral,
    varrier_lateral_lpv,
    varrier_uncertainty,
    white_speyer,
)
from fdikit.plants.target_tracking import tracking_A
from fdikit.studies.path1996 import path_bank, path_fault_model, path_runs

N = 10


_bank_cache: list = []


def _BANK():
    """The PATH bank, designed once (the path_runs cases check their arguments before simulating)."""
    if not _bank_cache:
        _bank_cache.append(path_bank())
    return _bank_cache[0]


def _diag(n=N):
    t = np.arange(n) * 0.1
    alarm = np.zeros(n, bool)
    return Diagnosis(t=t, alarm=alarm, fired=alarm[:, None], names=("r",), isolated=np.full(n, "none"))


CASES = [
    # ------------------------------------------------------------------ plant lookup and constructors
    case("get-plant-unknown", lambda: get_plant("path13"), ParameterError, "path13", "known plants"),
    case("get-plant-not-string", lambda: get_plant(12), ParameterError, "12", "known plants"),
    case("get-plant-bad-kw", lambda: get_plant("msd", mass=3.0), ParameterError, "mass", "msd"),
    case("path12-tiny", lambda: path_vehicle_12("half"), ParameterError, "tiny", "'half'"),
    case("path14-tiny-none", lambda: path_vehicle_14(None), ParameterError, "tiny", "None"),
    case("rounding-intervals-13", lambda: rounding_intervals(13), ParameterError, "n_states", "13"),
    case("msd-k1-nan", lambda: msd(k1=float("nan")), ParameterError, "k1", "finite"),
    case("msd-m3-zero", lambda: msd(m3=0.0), ParameterError, "m3", "positive"),
    case("msd-k1-outside", lambda: msd(k1=5.0), ParameterError, "k1", "range"),
    case("msd-dt-zero", lambda: msd(dt=0.0), ParameterError, "dt", "positive"),
    case("msd-k1-string", lambda: msd(k1="stiff"), ParameterError, "k1", "number"),
    case("msd-matrices-f1-inf", lambda: msd_matrices(f1=float("inf")), ParameterError, "f1", "finite"),
    case("b747-model", lambda: b747_longitudinal("broken"), ParameterError, "model", "'broken'"),
    case("b747-a35", lambda: b747_longitudinal(a35="typo"), ParameterError, "a35", "'typo'"),
    case("b747-dt-negative", lambda: b747_longitudinal(dt=-0.01), ParameterError, "dt", "positive"),
    case("b747-set-dt-string", lambda: b747_model_set(dt="fast"), ParameterError, "dt", "number"),
    case("white-speyer-case", lambda: white_speyer("unstable"), ParameterError, "case", "'unstable'"),
    case("varrier-speed-zero", lambda: varrier_lateral(speed=0.0), ParameterError, "speed", "positive"),
    case("varrier-speed-list", lambda: varrier_lateral(speed=[10.0, 20.0]), ParameterError, "speed",
         "single number"),
    case("varrier-dt-zero", lambda: varrier_lateral(dt=0.0), ParameterError, "dt", "positive"),
    case("varrier-params-type", lambda: varrier_lateral(params={"m": 1.0}), ParameterError, "params",
         "VarrierParameters"),
    case("varrier-lpv-rho-star", lambda: varrier_lateral_lpv(rho_star=-1.0), ParameterError, "rho_star",
         "positive"),
    case("varrier-uncertainty-mode", lambda: varrier_uncertainty(mode="wild"), ParameterError, "mode", "'wild'"),
    case("varrier-uncertainty-scale", lambda: varrier_uncertainty(scale=float("nan")), ParameterError, "scale",
         "finite"),
    case("rho-from-speed-negative", lambda: rho_from_speed(-3.0), ParameterError, "speed", "positive"),
    case("f16xl-gust-noise", lambda: f16xl_gust(pitch_rate_noise=-1.0), ParameterError, "pitch_rate_noise", ">= 0"),
    case("f16xl-gust-gain-nan", lambda: f16xl_gust(gust_gain=float("nan")), ParameterError, "gust_gain", "finite"),
    case("tracking-dt-zero", lambda: tracking_A(0.0), ParameterError, "dt", "positive"),
    case("msd-matrices-m3-string", lambda: msd_matrices(m3="heavy"), ParameterError, "m3", "number"),
    case("b747-set-a35", lambda: b747_model_set(a35=None), ParameterError, "a35", "None"),
    case("rho-from-speed-string", lambda: rho_from_speed("fast"), ParameterError, "speed", "number"),
    case("get-plant-kw-type", lambda: get_plant("msd", k1="soft"), ParameterError, "k1", "number"),
    case("tracking-dt-string", lambda: tracking_A("1s"), ParameterError, "dt", "number"),
    # single_track.py (fixes pending in that module)
    case("single-track-params-type", lambda: single_track(20.0, params="x"), ParameterError, "params",
         "SingleTrackParameters"),
    case("single-track-lpv-dt-zero", lambda: single_track_lpv(dt=0.0), ParameterError, "dt", "positive"),
    case("understeer-params-type", lambda: understeer_gradient("x"), ParameterError, "params",
         "SingleTrackParameters"),
    case("single-track-parameters-string", lambda: SingleTrackParameters(m="heavy"), ParameterError, "m", "number"),
    # ------------------------------------------------------------------ PATH monitor
    case("path-fault-model-13", lambda: path_fault_model(13), ParameterError, "n_states", "13"),
    case("path-bank-dt-negative", lambda: path_bank(dt=-0.01), ParameterError, "dt", "positive"),
    case("path-bank-eig-unknown", lambda: path_bank(poles={"filter9": [-1.0]}), ParameterError,
         "poles", "filter9"),
    case("path-runs-not-bank", lambda: path_runs("bank"), ParameterError, "bank", "PathBank"),
    case("path-runs-duration", lambda: path_runs(_BANK(), duration=0.0), ParameterError, "duration", "positive"),
    case("path-runs-count", lambda: path_runs(_BANK(), runs_per_fault=-1), ParameterError, "runs_per_fault",
         "non-negative"),
    case("path-runs-noise", lambda: path_runs(_BANK(), noise_fraction=float("nan")), ParameterError,
         "noise_fraction", "finite"),
    case("path-runs-onset-after-end", lambda: path_runs(_BANK(), duration=2.0, onset=5.0), ParameterError, "onset",
         "duration"),
    # ------------------------------------------------------------------ metrics
    case("score-length", lambda: score(np.full(N + 2, "none"), _diag()), DataError, "truth", "samples"),
    case("score-not-diagnosis", lambda: score(np.full(N, "none"), "alarm"), ParameterError, "diagnosis",
         "Diagnosis"),
    case("score-truth-2d", lambda: score(np.full((N, 2), "none"), _diag()), DataError, "truth", "1-D"),
    case("summarize-empty", lambda: summarize([]), DataError, "no scores"),
    case("summarize-not-scores", lambda: summarize([1, 2]), ParameterError, "scores", "Score"),
    case("confusion-empty", lambda: confusion_matrix([]), DataError, "no scores"),
    case("vaf-shapes", lambda: vaf([1.0, 2.0, 3.0], [1.0, 2.0]), DataError, "vaf", "shapes"),
    case("vaf-nan", lambda: vaf([1.0, np.nan, 3.0], [1.0, 2.0, 3.0]), DataError, "reference", "finite"),
    case("vaf-string", lambda: vaf(["a", "b"], [1.0, 2.0]), DataError, "reference", "number"),
    case("score-truth-none-label", lambda: score(np.array(["none", None] * 5, dtype=object), _diag()), DataError,
         "truth", "string"),
    case("vaf-empty", lambda: vaf([], []), DataError, "vaf", "2+ samples"),
    case("vaf-constant", lambda: vaf([1.0, 1.0, 1.0], [1.0, 2.0, 3.0]), DataError, "constant"),
]


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
