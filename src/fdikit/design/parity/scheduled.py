"""Speed-scheduled (LPV) parity fault detection filter (van der Ploeg 2018, Sec. 3-3, Thm 3-3.4; Sec. 4-3-4).

The model varies with a measured parameter ``ρ`` (the longitudinal speed): ``H_k(q)[x] +
L_k(q)[z] + F_k(q)[f] = 0`` (3.11), sampled with the parameter frozen over each sample
("complete discretisation", Sec. 4-3-4).  At every step ``k`` the filter rebuilds the
time-indexed bar matrices of Lemma 3-3.2 from the models at the instants of its window and
takes the parity row of Theorem 3-3.4::

    N̄_k*(γ) = ½ F̄_{k,j}ᵀ (I + γ H̄_k H̄_kᵀ)⁻¹                                    (3.17)

or its exact limit ``γ → ∞``, ``N̄_k = ½ (P_k F̄_{k,j})ᵀ`` with ``P_k`` the orthogonal projector
onto the left null space of ``H̄_k`` (``gamma=None``).  ``N̄_k`` is then
scaled so that ``Σ N̄_k F̄_k = −d(1)`` ((4.18)–(4.19): the fault-to-residual DC gain is 1),
and the residual follows the input-output form of Corollary 3-3.5::

    d(q) r = w,   w(k) = N̄_k L̄_k [z(τ_0); …; z(τ_{d_N + d_L})],   τ_i = k − deg d + i

so ``r(k)`` uses ``z`` and ``ρ`` up to ``k − 1`` only (strictly proper).

Errata and reconstruction choices (van der Ploeg 2018, Thm 3-3.4, Sec. 4-3-4; the window ordering of
Lemma 3-3.2 is in :mod:`fdikit.design.parity.scheduled_window`):

* ``N_k(1) F_k(1)`` in (4.18) is read as ``Σ N̄_k F̄_k`` (the current coefficients);
* ``j`` must select a coefficient of ``F`` that reaches ``N_k(q) F_k(q)``: for the
  single-track model the ``q²`` column lies in the range of ``H̄_k`` (the fault at the last
  instant only moves the next state), so ``N̄_k ≈ 0`` there (Sec. 4-3-4); that choice raises
  :class:`DesignError`;
* ``d(q) = Π (q − p_i)`` with real poles, run as a cascade of first-order sections.

The window tools (time-indexed bar matrices, rank test (3.15), parity row (3.17)) are in
:mod:`fdikit.design.parity.scheduled_window`; the scheduled residual generator and its online stepper
in :mod:`fdikit.design.parity.scheduled_generator`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from fdikit.dae import dae_form
from fdikit.design.labels import residual_labels
from fdikit.design.parity.polynomial import parity_filter, real_poles
from fdikit.design.parity.polynomial_rank import target_fault
from fdikit.design.parity.scheduled_generator import Family, ScheduledResidualGenerator
from fdikit.design.parity.scheduled_window import lpv_parity_row
from fdikit.errors import DesignError, ModelError, ParameterError
from fdikit.model import FaultModel

__all__ = [
    "scheduled_parity_filter",
]


def scheduled_parity_filter(
    family: Family,
    reference: float,
    targets: str | Sequence[str] | None = None,
    *,
    degree: int | None = None,
    poles: float | Sequence[float] = 0.9048,
    gamma: float | None = None,
    column: int = 0,
    schedule: str = "speed",
    name: str | None = None,
    names: Sequence[str] | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
    grid: float | None = None,
) -> ScheduledResidualGenerator:
    """Speed-scheduled parity filter (van der Ploeg 2018, Thm 3-3.4, (3.17), (4.18); Sec. 4-3-4).

    Parameters
    ----------
    family : callable ``ρ -> FaultModel``
        Discrete models with the fault input, e.g. :func:`fdikit.plants.single_track.single_track_lpv`.
    reference : float
        Design point ``ρ`` for the degree search and the checks (e.g. ``70 / 3.6`` m/s).
    targets : str, optional
        The fault to detect, by fault name (default: the model's only fault).
    degree : int, optional
        ``d_N``; default the minimal degree at ``reference``.
    poles : float or sequence of float
        Real poles of ``d(q)`` (default 0.9048, repeated ``d_N + d_L + 1`` times).
    gamma : float or None
        Lagrange multiplier of (3.17) (the thesis uses 1e7); None (default) is the exact
        ``γ → ∞`` projection.
    column : int
        ``j``, the column of ``F̄_k`` (coefficient of ``q^j``) that (3.16) maximises; default 0.
    schedule : str
        Name of the trace column holding ``ρ`` (default ``"speed"``).
    name : str, optional
        Residual name (default ``r_<fault>``; the same as ``names=[name]``).
    names, isolates : optional
        The residual's name and the fault it isolates (default the target; None: detection only), as
        :func:`~fdikit.design.labels.residual_labels`: a one-element sequence or ``{residual: fault}``,
        checked against the model's fault names.
    grid : float, optional
        Spacing ``h`` (units of ``ρ``, e.g. m/s) of a grid ``reference + i h`` on which ``family`` is
        evaluated; between nodes the DAE coefficients are interpolated linearly, error
        ``≤ h²/8 · max‖∂²M/∂ρ²‖`` per coefficient.  A measured (noisy) ``ρ`` is new at every sample, so
        the exact path (None, default) calls ``family(ρ)`` once per sample; the grid calls it once per
        node (range/h + 1 times).  For the single-track family ``h = 0.05`` m/s changes the residual by
        under 1e-4 of its size (tested); the grid is what makes a costly ``family`` usable on measured speed.

    Returns
    -------
    ScheduledResidualGenerator, the scheduled filter (its own ``generator``; ``reference``: the LTI design).

    Raises
    ------
    ParameterError
        ``family`` not callable; several targets or a bare signal name; ``name`` and ``names`` both given,
        bad ``names`` / ``isolates`` (see :func:`~fdikit.design.labels.residual_labels`); ``grid`` not positive.
    ModelError
        ``family(reference)`` not a discrete FaultModel, or ``isolates`` names a fault the model does not have.
    DesignError
        If the fault is not detectable at ``reference``, ``column`` is out of range or
        degenerate there, or there are fewer than ``d_N + d_L + 1`` poles.

    Examples
    --------
    >>> from fdikit.plants.single_track import single_track_lpv
    >>> gen = scheduled_parity_filter(single_track_lpv(), 70 / 3.6)
    >>> gen.degree, gen.window, gen.residuals
    (2, 3, ('r_steering_actuator',))
    >>> g = scheduled_parity_filter(single_track_lpv(), 70 / 3.6, names=["r_steer"], isolates=[None], grid=0.05)
    >>> g.residuals, g.isolates, g.grid
    (('r_steer',), (None,), 0.05)

    References
    ----------
    van der Ploeg 2018, Thm 3-3.4, (3.17), (4.18)–(4.19); Sec. 4-3-4.
    """
    if not callable(family):
        raise ParameterError(
            f"family must be a callable ρ -> discrete FaultModel (e.g. plants.single_track.single_track_lpv()), "
            f"got {type(family).__name__}"
        )
    if name is not None and names is not None:
        raise ParameterError("give the residual name once: names= (name= is its older spelling)")
    if grid is not None and (isinstance(grid, bool) or not isinstance(grid, (int, float, np.integer, np.floating))
                             or not (np.isfinite(grid) and grid > 0)):
        raise ParameterError(f"grid must be a positive spacing of the schedule (e.g. 0.05 m/s) or None (exact), "
                             f"got {grid!r}")
    model = family(reference)
    if not isinstance(model, FaultModel) or not model.is_discrete:
        raise ModelError(f"family({reference}) must return a discrete FaultModel, got {model!r}")
    dae = dae_form(model)
    fault = target_fault(dae, targets, "scheduled_parity_filter")
    ref = parity_filter(dae_form(model, [fault]), fault, degree=degree, poles=poles, name=name)
    min_poles = ref.degree + len(dae.L)
    p = real_poles(poles, min_poles)
    if p.size < min_poles:
        raise DesignError(f"the scheduled filter needs at least d_N + d_L + 1 = {min_poles} poles, got {p.size}")
    n_cols = ref.degree + len(dae.F)
    if not 0 <= int(column) < n_cols:
        raise DesignError(f"column must index F̄ (0 … {n_cols - 1}), got {column}")
    fast = callable(getattr(family, "dae_matrices", None))
    if fast:
        mats = family.dae_matrices(reference)
        want = (*ref.dae.H, *ref.dae.L, *ref.dae.F)
        fast = len(mats) == len(want) and all(np.shape(a) == b.shape and np.allclose(a, b) for a, b in zip(mats, want))
    residuals, isolated = residual_labels(model, 1, names, isolates, default_names=ref.generator.residuals,
                                          default_isolates=(fault,))
    gen = ScheduledResidualGenerator(
        family=family, fault=fault, degree=ref.degree, poles=p, gamma=None if gamma is None else float(gamma),
        column=int(column), controls=model.controls, outputs=model.outputs, residuals=residuals,
        isolates=isolated, dt=float(model.dt), schedule=schedule, reference=ref, fast_path=fast,
        grid=None if grid is None else float(grid), design_point=float(reference),
    )
    Hb, _, Fb = gen.bar_matrices(np.full((1, ref.degree + 1), float(reference)))
    Fj = Fb[0, :, gen.column]
    if np.linalg.norm(lpv_parity_row(Hb[0], Fj)) <= 1e-8 * np.linalg.norm(Fj):
        raise DesignError(f"column j={column} of F̄ lies in the range of H̄ at the design point (P F̄_j = 0), so "
                          "(3.17) gives N̄ ≈ 0 (Sec. 4-3-4: the q² column); choose column=0")
    gen.rows(np.full((1, ref.degree + 1), float(reference)))  # e.g. a bad gamma fails now, not at run time
    return gen
