"""H∞-bounded Beard–Jones detection filters (Douglas et al. 1996, App. C).

The filter keeps the exact detection-space structure of a Beard–Jones filter — every
fault's space ``W_i`` is invariant under ``A + LC`` — and spends the gain freedom that
is left on bounding the H∞ norm from the disturbance/noise ``ω`` to the fault residuals.

* **Gain family** (Prop. C.3/C.4, (c.2), (c.7)): ``L`` keeps every ``W_i`` invariant iff
  ``L = Σ_i (−A W_i F̂_i + W_i α_i) H_i + β H_0`` with free ``α_i`` (ν_i x k_i) and ``β``
  (n x k_0); ``F̂_i`` are right singular vectors of ``C W_i`` (identity when ``C W_i`` is
  monic) and ``H_i`` the natural projections (k_i x p) onto the coordinates of ``C W_i F̂_i``
  along the other images and their orthogonal complement (``Im H_0``).
* **Modified Riccati equation** (Prop. C.7, (c.17)–(c.18)) for the error system
  ``e' = (A + LC) e − (B + LD) ω``, ``z = H (C e − D ω)``: with ``L̂ = −Σ A W_i F̂_i H_i``,
  ``Â = A + L̂C``, ``B̂ = B + L̂D``, ``C₂ = 𝐓 C``, ``D₂₁ = 𝐓 D`` (𝐓 stacks ``H_1 … H_q, H_0``),
  ``V = D₂₁D₂₁ᵀ``, ``C_z = HC``, ``D_z = HD``, a ``Y > 0`` with ::

      0 = Ã Y + Y Ãᵀ + Q̃ − Y R̃ Y + Δ(Y) Ṽ Δ(Y)ᵀ

  gives ``α_i = P_{W_i} K Θ_i``, ``α_0 = K Θ_0``, ``K = −(Y C̃ᵀ + B̃) Ṽ⁻¹``, and
  ``‖T_zω‖∞ ≤ (γ² + σ²_max(HD))^½``.  ``Δ(Y)`` has blocks ``−(I − P_{W_i}) K Θ_i`` (and 0 for
  block 0); ``P_{W_i}`` is the orthogonal projector onto ``W_i`` (the report leaves its
  kernel open).  No Hamiltonian exists; as in App. C.5 the equation is solved by
  integrating the modified differential Riccati equation ``Ẏ = (…)`` to steady state from
  the stabilising solution of the equation without its extra term.

  **Erratum.** Theorem C.5 (c.14) writes the cross term as ``(Y C_zᵀ + B D_zᵀ)`` with the
  plant's ``B``; the bounded-real lemma needs the closed-loop input matrix ``B + LD``
  there.  With the printed term the bound can fail: on the reconstructed F-16XL example at
  γ = 1.2 the printed (c.18) gives ``‖T_zω‖∞ = 1.2457 > 1.2416``.  ``form='corrected'``
  (default) keeps the report's construction but completes the square with the correct
  cross term: ``Ṽ = V + γ⁻² D₂₁D_zᵀD_zD₂₁ᵀ``, ``C̃ = C₂ + γ⁻² D₂₁D_zᵀC_z``,
  ``B̃ = B̂(D₂₁ᵀ + γ⁻² D_zᵀD_zD₂₁ᵀ)``; then ``Ã = Â + γ⁻²B̂D_zᵀC_z − B̃Ṽ⁻¹C̃``,
  ``Q̃ = B̂(I + γ⁻²D_zᵀD_z)B̂ᵀ − B̃Ṽ⁻¹B̃ᵀ``, ``R̃ = C̃ᵀṼ⁻¹C̃ − γ⁻²C_zᵀC_z``, and the bound holds.
  ``form='printed'`` is (c.18) as printed (``Ṽ = V``, ``C̃ = C₂``, ``B̃ = B̂D₂₁ᵀ``); it
  reproduces the report's filter eigenvalues.
* **Fault enhancement** (App. C.4, (c.19)–(c.26), ``T = ∞``): see :func:`enhancement_direction`.

Sign convention: the equations above are in the report's sign — its gain ``L`` is that of
``A + LC`` and its residual is ``C x̂ − y``.  :attr:`HinfDesign.gain` is fdikit's observer gain
(``x̂' = A x̂ + Bu u + L (y − C x̂ − Du u)``, state matrix ``A − LC``), the negative of the
report's matrix, which stays available as :attr:`HinfDesign.report_gain`; the residual is
``z = 𝐇 (y − C x̂ − Du u)`` (the negative of the report's).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.linalg

from fdikit import linalg, validate
from fdikit.design.labels import label_generator
from fdikit.design.observers.detection_gain import DetectionGainFamily, detection_gain_family
from fdikit.design.observers.full_order import observer_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = [
    "HinfDesign",
    "hinf_detection_filter",
    "Enhancement",
    "enhancement_direction",
]


# ---------------------------------------------------------------------- (c.18) modified Riccati equation
@dataclass(frozen=True, eq=False)
class _Riccati:
    """The data of (c.18): ``0 = ÃY + YÃᵀ + Q̃ − YR̃Y + Δ(Y) Ṽ Δ(Y)ᵀ``."""

    At: np.ndarray
    Qt: np.ndarray
    Rt: np.ndarray
    Vt: np.ndarray
    Vinv: np.ndarray
    Ct: np.ndarray
    Bt: np.ndarray
    blocks: tuple[tuple[slice, np.ndarray], ...]  # (columns of block i, I − P_{W_i})

    def gain(self, Y: np.ndarray) -> np.ndarray:
        """Unconstrained ``K = −(Y C̃ᵀ + B̃) Ṽ⁻¹`` (n x p, columns in the order of 𝐓)."""
        return -(Y @ self.Ct.T + self.Bt) @ self.Vinv

    def delta(self, Y: np.ndarray) -> np.ndarray:
        """``Δ = G − K``: blocks ``−(I − P_{W_i}) K Θ_i``, zero on block 0."""
        K, out = self.gain(Y), np.zeros((Y.shape[0], self.Vt.shape[0]))
        for cols, Pperp in self.blocks:
            out[:, cols] = -Pperp @ K[:, cols]
        return out

    def residual(self, Y: np.ndarray) -> np.ndarray:
        Dl = self.delta(Y)
        R = self.At @ Y + Y @ self.At.T + self.Qt - Y @ self.Rt @ Y + Dl @ self.Vt @ Dl.T
        return (R + R.T) / 2

    def scale(self, Y: np.ndarray) -> float:
        return float(np.linalg.norm(self.At @ Y) + np.linalg.norm(self.Qt) + np.linalg.norm(Y @ self.Rt @ Y) + 1e-300)


def _riccati_data(fam: DetectionGainFamily, B, D, gamma, form) -> _Riccati:
    A, C = fam.A, fam.C
    n = A.shape[0]
    T = fam.coordinates
    Lh = -fam.base_gain
    Ah, Bh = A + Lh @ C, B + Lh @ D  # Lh: the report's L̂ (c.17h)
    C2, D21 = T @ C, T @ D
    k = sum(H.shape[0] for H in fam.residual_maps.values())
    Cz, Dz = C2[:k], D21[:k]
    g2 = gamma ** -2.0
    V = D21 @ D21.T
    if form == "printed":
        Vt, Ct, Bt = V, C2, Bh @ D21.T
    else:
        Vt = V + g2 * D21 @ Dz.T @ Dz @ D21.T
        Ct = C2 + g2 * D21 @ Dz.T @ Cz
        Bt = Bh @ (D21.T + g2 * Dz.T @ Dz @ D21.T)
    Vinv = np.linalg.inv(Vt)
    At = Ah + g2 * Bh @ Dz.T @ Cz - Bt @ Vinv @ Ct
    Qt = Bh @ Bh.T + g2 * Bh @ Dz.T @ Dz @ Bh.T - Bt @ Vinv @ Bt.T
    Rt = Ct.T @ Vinv @ Ct - g2 * Cz.T @ Cz
    blocks, start = [], 0
    for name, W in fam.spaces.items():
        kk = fam.residual_maps[name].shape[0]
        P = W @ np.linalg.solve(W.T @ W, W.T)
        blocks.append((slice(start, start + kk), np.eye(n) - P))
        start += kk
    return _Riccati(At, (Qt + Qt.T) / 2, (Rt + Rt.T) / 2, Vt, Vinv, Ct, Bt, tuple(blocks))


def _stabilising_are(ric: _Riccati, gamma: float) -> np.ndarray:
    """Stabilising solution of ``ÃY + YÃᵀ + Q̃ − YR̃Y = 0`` (R̃ indefinite) by the ordered Hamiltonian Schur form."""
    n = ric.At.shape[0]
    Ham = np.block([[ric.At.T, -ric.Rt], [-ric.Qt, -ric.At]])
    # the test for eigenvalues on the imaginary axis runs on the diagonally balanced matrix: with outputs of very
    # different units (kg next to rad/s) ‖Ham‖ is dominated by one block and a tolerance relative to it would call
    # eigenvalues of real part ≈ 1 "on the axis" (a similarity: the eigenvalues are the same)
    balanced, _ = scipy.linalg.matrix_balance(Ham, permute=False)
    ev = scipy.linalg.eigvals(balanced)
    tol = 1e-9 * max(np.linalg.norm(balanced, 1), 1.0)
    if np.any(np.abs(ev.real) <= tol):
        raise DesignError(
            f"the Riccati equation of (c.18) without its extra term has no stabilising solution for gamma = {gamma:g} "
            "(Hamiltonian eigenvalues on the imaginary axis); increase gamma"
        )
    _, U, sdim = scipy.linalg.schur(Ham, sort="lhp")
    if sdim != n:
        raise DesignError(f"the Hamiltonian of (c.18) has {sdim} stable eigenvalues, need {n}; increase gamma")
    Y = np.linalg.solve(U[:n, :n].T, U[n:, :n].T).T
    return (Y + Y.T) / 2


def _integrate(ric: _Riccati, Y0, gamma, horizon, steady_tol, polish) -> tuple[np.ndarray, float]:
    """Integrate ``Ẏ = (c.18)(Y)`` (LSODA) from ``Y0`` to a steady state, then polish it by Newton (hybr)."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import root

    n = Y0.shape[0]
    iu = np.triu_indices(n)

    def unpack(y):
        Y = np.zeros((n, n))
        Y[iu] = y
        return Y + np.triu(Y, 1).T

    def rhs(_t, y):
        return ric.residual(unpack(y))[iu]

    def steady(_t, y):
        Y = unpack(y)
        return np.linalg.norm(ric.residual(Y)) - steady_tol * ric.scale(Y)

    def escape(_t, y):
        return np.abs(y).max() - 1e8 * max(1.0, np.abs(Y0).max())

    steady.terminal = escape.terminal = True
    sol = solve_ivp(rhs, (0.0, horizon), Y0[iu], method="LSODA", rtol=1e-8,
                    atol=1e-12 * max(1.0, np.abs(Y0).max()), events=[steady, escape])
    if sol.status == -1 or sol.t_events[1].size or not np.all(np.isfinite(sol.y[:, -1])):
        raise DesignError(
            f"the modified Riccati differential equation (c.18) escapes to infinity near t = {sol.t[-1]:.3g} "
            f"for gamma = {gamma:g}: no steady state exists from the ARE start; increase gamma"
        )
    if not sol.t_events[0].size:
        Y = unpack(sol.y[:, -1])
        raise DesignError(
            f"the modified Riccati differential equation (c.18) did not settle within horizon = {horizon:g} s "
            f"(relative residual {np.linalg.norm(ric.residual(Y)) / ric.scale(Y):.1e}); raise horizon or gamma"
        )
    y = sol.y[:, -1]
    if polish:
        fit = root(lambda v: rhs(0.0, v), y, method="hybr", options={"xtol": 1e-14})
        if np.linalg.norm(rhs(0.0, fit.x)) < np.linalg.norm(rhs(0.0, y)):
            y = fit.x
    return unpack(y), float(sol.t[-1])


@dataclass(frozen=True, eq=False)
class HinfDesign(FieldReport):
    """An H∞-bounded detection filter (Douglas et al. 1996, Prop. C.7) and its design report.

    Attributes
    ----------
    generator : residuals ``<fault>[k]`` = the coordinates ``z_i = H_i r`` (c.11), each tied to its fault.
    gain : observer gain ``L``: the generator's state matrix is ``A − LC`` (:attr:`report_gain` = ``−L`` is
        the report's matrix, of ``A + LC``).
    gamma, form : the design parameter and the Riccati form (``'corrected'`` or ``'printed'``).
    riccati : the steady-state ``Y`` of (c.18); ``initial_riccati`` the ARE solution the integration started from.
    riccati_residual : ``‖(c.18)(Y)‖_F`` relative to the size of its terms.
    settling_time : integration time of the differential Riccati equation to steady state.
    alphas : ``α_i`` (ν_i x k_i) by fault; ``alpha0`` (n x k_0).
    poles : eigenvalues of ``A − LC``.
    hinf_norm, peak_frequency : ``‖T_zω‖∞`` (SLICOT AB13DD via python-control) and where it peaks (rad/s).
    bound : ``(γ² + σ²_max(HD))^½``.
    family : the gain family (detection spaces ``W_i``, maps ``H_i``, projectors, ``L̂``).
    disturbances : names of the inputs that form ``ω``; ``B``, ``D`` their matrices.
    model : the FaultModel the design was made for (keyword-only; set by :func:`hinf_detection_filter`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.f16xl import f16xl_gust, F16XL_DRYDEN_GAIN
    >>> m = f16xl_gust(gust_gain=F16XL_DRYDEN_GAIN)
    >>> d = hinf_detection_filter(m, ["y_Az_sensor", "elevon_actuator"], gamma=1.5)
    >>> d.generator.residuals, d.form, bool(np.allclose(d.report_gain, -d.gain))
    (('y_Az_sensor[0]', 'y_Az_sensor[1]', 'elevon_actuator[0]'), 'corrected', True)

    References
    ----------
    Douglas et al. 1996, App. C.3, Prop. C.7, (c.17)–(c.18); App. C.5.
    """

    generator: ResidualGenerator
    gain: np.ndarray
    gamma: float
    form: str
    riccati: np.ndarray
    initial_riccati: np.ndarray
    riccati_residual: float
    settling_time: float
    alphas: dict[str, np.ndarray]
    alpha0: np.ndarray
    poles: np.ndarray
    hinf_norm: float
    peak_frequency: float
    bound: float
    family: DetectionGainFamily
    disturbances: tuple[str, ...]
    B: np.ndarray
    D: np.ndarray

    detection_spaces = property(lambda self: self.family.spaces, doc="``W_i`` by fault.")
    residual_maps = property(lambda self: self.family.residual_maps, doc="``H_i`` (k_i x p) by fault.")
    projectors = property(lambda self: self.family.projectors, doc="``C W_i F̂_i H_i`` (p x p) by fault.")
    report_gain = property(lambda self: -self.gain, doc="The report's gain: ``L`` of ``A + LC`` (``= −gain``).")

    def error_system(self):
        """``T_zω``: ``e' = (A − LC) e + (B − LD) ω``, ``z = HC e + HD ω`` as a :class:`control.StateSpace`.

        (ω is taken with the opposite sign of (c.10); norms are unchanged.)
        """
        import control

        H = np.vstack(list(self.family.residual_maps.values()))
        A, C, L = self.family.A, self.family.C, self.gain
        return control.ss(A - L @ C, self.B - L @ self.D, H @ C, H @ self.D)

    def report(self) -> dict:
        """``gain`` (the attribute ``gain``), ``gamma``, ``form``, ``poles``, ``hinf_norm`` (attained ``‖T_zω‖∞``),
        ``peak_frequency``, ``bound`` (``(γ² + σ²_max(HD))^½``), ``riccati`` (``Y``), ``riccati_residual``,
        ``settling_time``, ``detection_spaces`` (``W_i``) and ``projectors``, ``disturbances`` (names of ω)."""
        return {"gain": self.gain, "gamma": self.gamma, "form": self.form, "poles": self.poles,
                "hinf_norm": self.hinf_norm, "peak_frequency": self.peak_frequency, "bound": self.bound,
                "riccati": self.riccati, "riccati_residual": self.riccati_residual,
                "settling_time": self.settling_time, "detection_spaces": self.detection_spaces,
                "projectors": self.projectors, "disturbances": self.disturbances}


def _omega(model: FaultModel, disturbances):
    pool = model.disturbances + model.noise
    names = tuple(pool) if disturbances is None else tuple(disturbances)
    if not names:
        raise DesignError("the model has no disturbance or noise inputs (groups 'd', 'w'); the H∞ filter needs ω")
    cols = []
    for nm in names:
        if nm not in pool:
            raise ParameterError(f"{nm!r} is not a disturbance or noise input; the model has {list(pool)}")
        g = "d" if nm in model.disturbances else "w"
        cols.append((model.b(g)[:, model.index(g, nm)], model.d(g)[:, model.index(g, nm)]))
    return names, np.hstack([c[0] for c in cols]), np.hstack([c[1] for c in cols])


def hinf_detection_filter(
    model: FaultModel,
    targets: Mapping[str, np.ndarray] | Sequence[str] | str,
    *,
    gamma: float,
    disturbances: Sequence[str] | None = None,
    form: Literal["corrected", "printed"] = "corrected",
    horizon: float = 1e6,
    steady_tol: float = 1e-9,
    polish: bool = True,
    rtol: float | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
) -> HinfDesign:
    """H∞-bounded detection filter (Douglas et al. 1996, App. C, Prop. C.7, (c.17)–(c.18)).

    Parameters
    ----------
    model : continuous FaultModel; ``ω`` are its disturbance and noise inputs (``x' = … + B ω``,
        ``y = … + D ω``); ``D Dᵀ`` must be invertible (every output noisy).
    targets : the faults to detect: fault names or a mapping name → ``F`` (see
        :func:`detection_gain_family`).  Sensor faults (``'<output>_sensor'``) give ``[F¹, A F¹]``
        with ``C F¹ = e_i``: the residual coordinates are then in output units, as in App. C.5.
    gamma : the H∞ parameter γ > 0 of (c.18).
    disturbances : names of the inputs forming ω (default: every ``d`` and ``w`` input).
    form : ``'corrected'`` (default; the bound is guaranteed) or ``'printed'`` ((c.18) as printed,
        reproduces App. C.5; the bound may fail, see the module docstring).
    horizon, steady_tol : integration limit (s) and relative steady-state tolerance of the
        differential Riccati equation; ``polish`` refines the steady state by Newton's method.
    rtol : relative rank tolerance of the subspace computations.
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<fault>[k]`` tied to each target), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    HinfDesign
        Generator, observer gain, ``Y``, ``α_i``, the attained ``‖T_zω‖∞`` and its bound.

    Raises
    ------
    ParameterError
        Not a FaultModel; γ not a positive finite number; an unknown ``form``; ``horizon`` or ``steady_tol``
        not positive; a ``disturbances`` name that is no ``d``/``w`` input; a bare signal name.
    ModelError
        A discrete model, or a name that is not a fault of the model.
    DesignError
        No ``d``/``w`` input; ``D Dᵀ`` singular; ``Â − B̂D₂₁ᵀV⁻¹C₂`` with imaginary-axis eigenvalues (Prop. C.7);
        no stabilising ARE solution to start from; the Riccati flow escapes or does not settle
        (γ too small); ``Y`` not positive definite; an unstable filter; the geometric conditions
        of :func:`detection_gain_family`.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.f16xl import f16xl_gust, F16XL_DRYDEN_GAIN
    >>> m = f16xl_gust(gust_gain=F16XL_DRYDEN_GAIN)
    >>> d = hinf_detection_filter(m, ["y_Az_sensor", "elevon_actuator"], gamma=1.5)
    >>> bool(d.hinf_norm <= d.bound), bool(np.all(d.poles.real < 0))
    (True, True)

    References
    ----------
    Douglas et al. 1996, App. C.3, Prop. C.7, (c.17)–(c.18); Thm. C.5, (c.14) (erratum above).
    """
    validate.instance("model", model, FaultModel)
    gamma = validate.number("gamma", gamma, finite=False)
    if not (np.isfinite(gamma) and gamma > 0):
        raise ParameterError(f"gamma must be a positive number, got {gamma!r}")
    if form not in ("corrected", "printed"):
        raise ParameterError(f"form must be 'corrected' or 'printed', got {form!r}")
    horizon = validate.positive("horizon", horizon)
    steady_tol = validate.positive("steady_tol", steady_tol)
    import control

    fam = detection_gain_family(model, targets, rtol)
    omega_names, B, D = _omega(model, disturbances)
    p = model.p
    if linalg.rank(D @ D.T) < p:
        raise DesignError(
            f"D Dᵀ of the disturbance/noise inputs {list(omega_names)} is singular (rank {linalg.rank(D @ D.T)} "
            f"< p = {p}); "
            "Prop. C.7 needs V = D₂₁D₂₁ᵀ invertible: give every output its own noise input"
        )
    T = fam.coordinates
    C2, D21 = T @ model.C, T @ D
    Ah, Bh = model.A - fam.base_gain @ model.C, B - fam.base_gain @ D  # the report's Â, B̂ (c.17)
    Abar = Ah - Bh @ D21.T @ np.linalg.solve(D21 @ D21.T, C2)
    ev = scipy.linalg.eigvals(Abar)
    if np.any(np.abs(ev.real) <= 1e-10 * max(np.linalg.norm(Abar, 1), 1.0)):
        raise DesignError(f"Â − B̂D₂₁ᵀV⁻¹C₂ has eigenvalues on the imaginary axis {ev[np.abs(ev.real) < 1e-8]}; "
                          "Prop. C.7 excludes this: change the noise model")
    ric = _riccati_data(fam, B, D, float(gamma), form)
    Y0 = _stabilising_are(ric, gamma)
    Y, t_end = _integrate(ric, Y0, gamma, horizon, steady_tol, polish)
    lam = np.linalg.eigvalsh(Y)
    if lam[0] <= 1e-12 * max(lam[-1], 1e-300):
        raise DesignError(f"the steady state of (c.18) is not positive definite (eigenvalues {lam}); increase gamma")
    K = ric.gain(Y)
    G = K + ric.delta(Y)
    L = fam.base_gain - G @ T  # the observer gain; the report's L = L̂ + G 𝐓 is its negative
    alphas, start = {}, 0
    for k, W in fam.spaces.items():
        kk = fam.residual_maps[k].shape[0]
        alphas[k] = np.linalg.lstsq(W, G[:, start : start + kk], rcond=None)[0]
        start += kk
    alpha0 = G[:, start:]
    poles = scipy.linalg.eigvals(model.A - L @ model.C)
    if np.any(poles.real >= 0):
        raise DesignError(f"the H∞ detection filter is unstable (poles {np.round(poles, 6).tolist()}); increase gamma")
    H = np.vstack(list(fam.residual_maps.values()))
    sys = control.ss(model.A - L @ model.C, B - L @ D, H @ model.C, H @ D)
    norm, peak = control.linfnorm(sys)
    bound = float(np.sqrt(gamma**2 + np.linalg.norm(H @ D, 2) ** 2))
    res_names, iso = [], []
    for k, Hk in fam.residual_maps.items():
        res_names += [f"{k}[{j}]" for j in range(Hk.shape[0])]
        iso += [k] * Hk.shape[0]
    gen = label_generator(observer_generator(model, L, res_names, H.T), model, names, isolates,
                          default_isolates=iso)
    rel = float(np.linalg.norm(ric.residual(Y)) / ric.scale(Y))
    return HinfDesign(gen, L, float(gamma), form, Y, Y0, rel, t_end, alphas, alpha0, poles, float(norm),
                      float(peak), bound, fam, omega_names, B, D, model=model)


# ---------------------------------------------------------------------- (c.19)–(c.26) fault enhancement
@dataclass(frozen=True, eq=False)
class Enhancement(FieldReport):
    """A fault-enhancing residual direction (Douglas et al. 1996, App. C.4, (c.26), T = ∞).

    Attributes
    ----------
    fault : the fault whose residual ``z_i`` is combined.
    direction : unit ``q`` (k_i,); the enhanced scalar residual is ``qᵀ z_i``.
    ratio : ``λ_max`` of (c.25)/(c.26): fault-to-disturbance residual energy ratio along ``q``.
    generator : the scalar residual ``qᵀ z_i`` as a generator (named ``<fault>[q]``).
    model : the FaultModel of the design (keyword-only; set by :func:`enhancement_direction`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.f16xl import f16xl_gust, F16XL_DRYDEN_GAIN
    >>> m = f16xl_gust(gust_gain=F16XL_DRYDEN_GAIN)
    >>> d = hinf_detection_filter(m, ["y_Az_sensor", "elevon_actuator"], gamma=1.5)
    >>> e = enhancement_direction(d, "y_Az_sensor")
    >>> e.fault, e.generator.residuals, e.direction.shape
    ('y_Az_sensor', ('y_Az_sensor[q]',), (2,))

    References
    ----------
    Douglas et al. 1996, App. C.4, (c.19)–(c.26).
    """

    fault: str
    direction: np.ndarray
    ratio: float
    generator: ResidualGenerator
    def report(self) -> dict:
        """``fault``, ``direction`` (unit ``q``) and ``ratio`` (fault-to-disturbance energy ratio along ``q``)."""
        return {"fault": self.fault, "direction": self.direction, "ratio": self.ratio}


def enhancement_direction(design: HinfDesign, fault: str, *, names: Sequence[str] | None = None,
        isolates: Sequence[str | None] | Mapping[str, str | None] | None = None) -> Enhancement:
    """Fault-enhancing direction of a multi-dimensional residual (Douglas et al. 1996, (c.19)–(c.26), T = ∞).

    On the reduced realisation of ``z_i`` (the factor space ``X / Σ_{j≠i} W_j``, coordinates
    ``Q`` orthonormal to the other spaces): ``Ā = Qᵀ(A − LC)Q``, ``F̄ = QᵀF_i``,
    ``B̄ = Qᵀ(B − LD)``, ``C̄ = H_i C Q`` (``L`` the observer gain :attr:`HinfDesign.gain`; the report
    writes ``A + LC`` with its own sign).  With the observability gramian ``O``
    (``ĀᵀO + OĀ + C̄ᵀC̄ = 0``) and the controllability gramians ``X_ω``, ``X_m`` of ``B̄``,
    ``F̄``, the worst-case initial states ``e_0ω``, ``e_0m`` are the eigenvectors of
    ``O X_ω`` and ``O X_m`` for their largest eigenvalues ((c.23), (c.24) as printed);
    ``X_0ω``, ``X_0m`` solve ``ĀX + XĀᵀ + e_0e_0ᵀ = 0`` and ``q`` is the eigenvector of the
    largest λ of ``(C̄X_0mC̄ᵀ) q = λ (C̄X_0ωC̄ᵀ) q`` (c.26).  The sign of ``q`` is fixed so that
    its largest entry is positive.

    Parameters
    ----------
    design : HinfDesign
        The result of :func:`hinf_detection_filter`.
    fault : str
        One of the design's faults (its residual ``z_i`` is combined).
    names, isolates : optional
        Residual names and the fault each residual isolates (default ``<fault>[q]`` tied to ``fault``), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    Enhancement
        The unit direction ``q``, the energy ratio ``λ_max`` and the scalar residual ``qᵀ z_i``.

    Raises
    ------
    ParameterError
        ``design`` not a HinfDesign, or ``fault`` not one of its faults.
    DesignError
        ``C̄X_0ωC̄ᵀ`` singular: (c.26) has no finite maximum.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.plants.f16xl import f16xl_gust, F16XL_DRYDEN_GAIN
    >>> m = f16xl_gust(gust_gain=F16XL_DRYDEN_GAIN)
    >>> d = hinf_detection_filter(m, ["y_Az_sensor", "elevon_actuator"], gamma=1.5)
    >>> e = enhancement_direction(d, "y_Az_sensor")
    >>> round(float(np.linalg.norm(e.direction)), 6), bool(e.ratio > 0)
    (1.0, True)

    References
    ----------
    Douglas et al. 1996, App. C.4, (c.19)–(c.26).
    """
    validate.instance("design", design, HinfDesign, "pass the result of hinf_detection_filter(...)")
    fam = design.family
    if fault not in fam.spaces:
        raise ParameterError(f"no fault {fault!r} in the design; faults are {list(fam.names)}")
    A, C, L = fam.A, fam.C, design.gain
    n = A.shape[0]
    others = [W for k, W in fam.spaces.items() if k != fault]
    Q = scipy.linalg.null_space(linalg.orth(np.hstack(others)).T) if others else np.eye(n)
    Ab = Q.T @ (A - L @ C) @ Q
    Cb = fam.residual_maps[fault] @ C @ Q
    Bb = Q.T @ (design.B - L @ design.D)
    Fb = Q.T @ fam.fault_maps[fault]
    lyap = scipy.linalg.solve_continuous_lyapunov
    O = lyap(Ab.T, -Cb.T @ Cb)

    def worst(X):
        w, v = scipy.linalg.eig(O @ X)
        return np.real(v[:, int(np.argmax(w.real))])

    e_w, e_m = worst(lyap(Ab, -Bb @ Bb.T)), worst(lyap(Ab, -Fb @ Fb.T))
    Sm = Cb @ lyap(Ab, -np.outer(e_m, e_m)) @ Cb.T
    Sw = Cb @ lyap(Ab, -np.outer(e_w, e_w)) @ Cb.T
    Sm, Sw = (Sm + Sm.T) / 2, (Sw + Sw.T) / 2
    if np.linalg.eigvalsh(Sw)[0] <= 1e-12 * max(np.abs(Sw).max(), 1e-300):
        raise DesignError(f"C̄X_0ωC̄ᵀ of {fault!r} is singular: the worst disturbance does not excite every residual "
                          "direction, (c.26) has no finite maximum")
    lam, V = scipy.linalg.eigh(Sm, Sw)
    q = V[:, -1] / np.linalg.norm(V[:, -1])
    q = q if q[np.argmax(np.abs(q))] > 0 else -q
    g = design.generator
    sizes = {k: Hk.shape[0] for k, Hk in design.family.residual_maps.items()}  # the rows of z_i, whatever the names
    start = sum(sizes[k] for k in list(sizes)[: list(sizes).index(fault)])
    rows = list(range(start, start + sizes[fault]))
    gen = ResidualGenerator(g.A, g.B, (q @ g.C[rows]).reshape(1, -1), (q @ g.D[rows]).reshape(1, -1),
                            g.controls, g.outputs, (f"{fault}[q]",), g.dt, (fault,))
    gen = label_generator(gen, design.model, names, isolates)
    return Enhancement(fault, q, float(lam[-1]), gen, model=design.model)
