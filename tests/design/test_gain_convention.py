"""The observer-gain convention of docs/ARCHITECTURE.md, checked on every observer-type design.

Every design's ``gain`` is ``L`` of ``x̂⁺ = A x̂ + Bu u + L (y − C x̂ − Du u)`` (continuous: ``x̂' = …``),
python-control's ``lqe``/``dlqe`` sign, so the residual generator's state matrix is ``A − L C``.  Seeds
that print another sign or form keep their matrix under its own name (``report_gain`` for Douglas et al.
1996 / Beard–Jones ``A + LC``, ``filter_gain`` for Murray 2012 Ch. 5 ``Φ(I − LC)``); this file checks only
the common one.

Excluded, because their generator is not an observer ``A − L C`` of the model with a gain field:

* ``uio`` / ``uio_bank`` (:class:`~fdikit.design.observers.uio.UIODesign`): the state is ``z = T x`` and
  the state matrix ``N = T A − K1 C`` (``T = I − H C``); there is no ``gain`` — ``K1``, ``K = K1 + N H`` and
  ``H`` are reported under the UIO's own names (Chen & Patton 1999).
* ``ltv_game_filter`` / ``ltv_detection_filter``: time-varying; the filter is an
  :class:`~fdikit.design.game.ltv_filter.LTVDetectionFilter` (its own runner integrates
  ``A(t) − L(t) C(t)``), not an LTI :class:`~fdikit.residuals.ResidualGenerator`; ``gain`` is a function of t.
* the parity designs (``fdikit.design.parity``) have no observer gain.

The reduced-order Goh filter (``goh_filter`` / ``goh_detector``) is an observer of the *reduced* plant
``(Γ₁ A Γ₁ᵀ, C Γ₁ᵀ)`` on ``η₁ = Γ₁ x``; it is checked there.
"""

from __future__ import annotations

import numpy as np
import pytest

from fdikit import FaultModel
from fdikit.design.game.discrete import dgtfdf, dgtmfdf
from fdikit.design.game.discrete_setup import discrete_game_setup
from fdikit.design.game.multi_fault import game_filter
from fdikit.design.game.reduced_order import goh_detector, goh_filter
from fdikit.design.game.single_fault import game_filter_bank, single_fault_game_filter
from fdikit.design.observers.beard_jones import beard_jones, restricted_diagonal
from fdikit.design.observers.full_order import kalman, observer
from fdikit.design.observers.hinf import hinf_detection_filter
from fdikit.fault_maps import resolve_faults
from fdikit.plants.f16xl import F16XL_DRYDEN_GAIN, f16xl_gust, f16xl_longitudinal
from fdikit.plants.white_speyer import white_speyer


def _second_order(dt=None):
    m = FaultModel(A=[[0.0, 1.0], [-2.0, -3.0]], C=[[1.0, 0.0]], Bu=[[0.0], [1.0]])
    return m if dt is None else m.discretize(dt)


def _random(discrete=False, seed=0):
    rng = np.random.default_rng(seed)
    n, p = 5, 3
    A = rng.standard_normal((n, n))
    if discrete:
        A = 0.9 * A / np.abs(np.linalg.eigvals(A)).max()
    model = FaultModel(A, rng.standard_normal((p, n)), Bu=rng.standard_normal((n, 1)), dt=1.0 if discrete else None)
    return model, {"f0": rng.standard_normal((n, 1)), "f1": rng.standard_normal((n, 1))}


def _two_target_discrete():
    rng = np.random.default_rng(1)
    A = rng.standard_normal((3, 3))
    A = 0.9 * A / np.abs(np.linalg.eigvals(A)).max()
    return FaultModel(A, rng.standard_normal((2, 3)), Bf=rng.standard_normal((3, 2)), faults=["f1", "f2"], dt=1.0)


def _full(model, design):
    """``(generator state matrix, A, C, L)`` of a full-order observer on the model's own state."""
    return [(design.generator.A, model.A, model.C, design.gain)]


def _observer(dt):
    m = _second_order(dt)
    return _full(m, observer(m, poles=[-5.0, -6.0] if dt is None else [0.5, 0.6]))


def _kalman(dt):
    m = _second_order(dt)
    return _full(m, kalman(m, Q=np.eye(2), R=1.0))


def _beard_jones(discrete):
    m, faults = _random(discrete)
    sets = {"f0": [0.5], "f1": [0.4]} if discrete else {"f0": [-1.5], "f1": [-2.5]}
    return _full(m, beard_jones(m, faults, poles=sets, complement_poles=[0.3, 0.2, 0.1] if discrete
                                else [-3.0, -4.0, -5.0]))


def _restricted_diagonal():
    m, faults = _random()
    return [c for d in restricted_diagonal(m, faults, poles=-np.arange(1.0, 6.0)).filters.values() for c in _full(m, d)]


def _hinf():
    m = f16xl_gust(gust_gain=F16XL_DRYDEN_GAIN)
    return _full(m, hinf_detection_filter(m, ["y_Az_sensor", "elevon_actuator"], gamma=1.5))


def _single_fault_game(discrete):
    if discrete:  # dispatches to Murray's DGTFDF: gain = Φ L (the observer gain), filter_gain = L
        m = white_speyer("stable-zero").discretize(0.01)
        d = single_fault_game_filter(m, "f1", ["f2"], gamma=1e-6, V=100.0, Q=2e-5, M=5.0, P0=1e-6, steps=400)
    else:
        m = white_speyer("unstable-extra-zero")
        d = single_fault_game_filter(m, "f1", ["f2"], gamma=1e-6, V=1.0, Q=1e-4, M=0.01)
    return _full(m, d)


def _game(discrete):
    if discrete:  # dispatches to Murray's DGTMFDF
        m = _two_target_discrete()
        d = game_filter(m, ["f1", "f2"], gamma=1.0, V=1.0, Q=0.1, M=1.0, K=1.0, N=1.0, P0=1.0, steps=40,
                        method="fixed-point", options={"max_radius": 0.9999})
    else:
        m = white_speyer("stable-extra-zero")
        d = game_filter(m, ["f1", "f2"], M=0.05, Q={"f1": 1e-3, "f2": 2e-3}, K=0.1, N={"f1": 5.0, "f2": 10.0})
    return _full(m, d)


def _game_bank():
    m = white_speyer("stable-extra-zero")
    bank = game_filter_bank(m, ["f1", "f2"], Q=1e-3, M=0.05)
    return [c for d in bank.filters.values() for c in _full(m, d)]


def _dgtfdf():
    m = white_speyer("stable-zero").discretize(0.01)
    st = discrete_game_setup(m, ["f1"], ["f2"], gamma=1e-6, Vbar=1e-4, Q=2e-5, M=5.0, P0=1e-6, steps=400)
    return _full(m, dgtfdf(st))


def _dgtmfdf():
    m = _two_target_discrete()
    st = discrete_game_setup(m, ["f1", "f2"], gamma=1.0, Vbar=1.0, Q=0.1, M=1.0, K=1.0, N=1.0, P0=1.0, steps=40)
    return _full(m, dgtmfdf(st, method="fixed-point", max_radius=0.9999))


def _reduced(model, d):
    """The Goh filter observes ``η₁ = Γ₁ x``: its plant is ``(Γ₁ A Γ₁ᵀ, C Γ₁ᵀ)``."""
    G1 = d.transformation[: d.order]
    return [(d.generator.A, G1 @ model.A @ G1.T, model.C @ G1.T, d.gain)]


def _goh_detector():
    m = white_speyer("unstable-extra-zero")
    return _reduced(m, goh_detector(m, "f1", ["f2"], V=1.0, Q=1e-4))


def _goh_filter():
    m = f16xl_longitudinal()
    faults = resolve_faults(m, ["y_theta_sensor", "elevon_actuator"]) | {"gust": m.Bd}
    return _reduced(m, goh_filter(m, faults, V=1.0, Q=0.5))


DESIGNS = {
    "observer (poles, continuous)": lambda: _observer(None),
    "observer (poles, discrete)": lambda: _observer(0.1),
    "kalman (continuous)": lambda: _kalman(None),
    "kalman (discrete)": lambda: _kalman(0.1),
    "beard_jones (continuous)": lambda: _beard_jones(False),
    "beard_jones (discrete)": lambda: _beard_jones(True),
    "restricted_diagonal (every member)": _restricted_diagonal,
    "hinf_detection_filter": _hinf,
    "single_fault_game_filter (continuous)": lambda: _single_fault_game(False),
    "single_fault_game_filter (discrete: DGTFDF)": lambda: _single_fault_game(True),
    "game_filter (continuous)": lambda: _game(False),
    "game_filter (discrete: DGTMFDF)": lambda: _game(True),
    "game_filter_bank (every member)": _game_bank,
    "dgtfdf": _dgtfdf,
    "dgtmfdf": _dgtmfdf,
    "goh_detector (reduced plant)": _goh_detector,
    "goh_filter (reduced plant)": _goh_filter,
}


@pytest.mark.parametrize("name", list(DESIGNS))
def test_generator_state_matrix_is_a_minus_lc(name):
    """``generator.A == A − gain · C`` to 1e-10 of ``‖A‖ + ‖L‖‖C‖`` (the rounding of forming the product)."""
    cases = DESIGNS[name]()
    assert cases
    for gen_A, A, C, L in cases:
        L = np.asarray(L)
        assert L.shape == (A.shape[0], C.shape[0])
        scale = np.linalg.norm(A, 2) + np.linalg.norm(L, 2) * np.linalg.norm(C, 2)
        np.testing.assert_allclose(gen_A, A - L @ C, rtol=0, atol=1e-10 * scale)
