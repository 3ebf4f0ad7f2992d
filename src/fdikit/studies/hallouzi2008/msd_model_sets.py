"""MSD benchmark with the CP and LV model sets next to the OD set (Hallouzi 2008, §3.6.2, Table 3.3, Figs 3.7–3.11).

The same simulated run (:func:`fdikit.studies.hallouzi2008.msd.simulate_msd`) is filtered by the augmented EKF
(Table 2.3)
on three model sets:

* **OD** (§3.3.2): :func:`fdikit.studies.hallouzi2008.msd.run_msd_filter`;
* **CP** (§3.4): the enclosing simplex of :func:`~fdikit.multimodel.cp_design.cp_model_set` on the
  same large set; the weights are projected on the simplex (every large-set model is a convex combination of
  the vertices); parameters are reconstructed by the nearest large-set model (3.51)–(3.52), hence quantised to
  the grid, as in Figs 3.7–3.8;
* **LV** (§3.5, (3.44)–(3.45)): one weight per parameter (k1, m3, f1, f2) in [0, 1] (box constraint, no sum);
  parameters by the maps (3.54)–(3.57), hence smooth.

Filter tuning as for the OD run (``Q = q_x I``, ``Q^μ = q_mu I``, ``P_0 = 1e-2 I``, ``P^μ_0 = I/12``).  Initial
weights (a thesis gap): those of the healthy centre model (k1 = m3 = 1, no fault) — for CP its convex weights
on the vertices, for LV ``μ = (0.5, 0.1, 0, 0)``.  The CP substitute's enclosing simplex is loose (its vertices
lie at 1/m3 ∈ [−12.8, 9.4], f ∈ [−4, 4]; Kanev's optimiser is not available): started from the uniform
weights, i.e. the simplex's unphysical centroid, or with ``P^μ_0 = I/12``, the EKF diverges (VAF of x2 and the
velocities 0–25 %), so the CP run uses ``P^μ_0 = 1e-2 I``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.errors import ParameterError
from fdikit.metrics import vaf
from fdikit.multimodel.convex import convex_model_set, limit_value_convex_set
from fdikit.multimodel.convex_ekf import augmented_ekf
from fdikit.multimodel.cp_design import CPModelSet, cp_model_set
from fdikit.multimodel.lv_design import LimitValueModelSet, limit_value_model_set
from fdikit.multimodel.model_set import nearest_model, unvectorize
from fdikit.multimodel.reconstruction import estimated_model_vector, lv_parameter, lv_reciprocal_parameter
from fdikit.plants.msd import MSD_RANGES, msd_matrices, msd_model_vectors, msd_parameter_grid
from fdikit.studies.hallouzi2008.msd import MSD_STATES, MSDSimulation, run_msd_filter

__all__ = ["msd_cp_model_set", "msd_lv_model_set", "ModelSetRun", "run_msd_model_set", "msd_table_3_3"]

_P0 = 1e-2


def _grid(grid_levels: int, fault_values) -> np.ndarray:
    if grid_levels < 2:
        raise ParameterError(f"grid_levels must be >= 2 so the grid holds both range limits, got {grid_levels}")
    (k_lo, k_hi), (m_lo, m_hi) = MSD_RANGES["k1"], MSD_RANGES["m3"]
    return msd_parameter_grid(np.linspace(k_lo, k_hi, grid_levels), np.linspace(m_lo, m_hi, grid_levels),
                              np.asarray(fault_values, float))


def msd_cp_model_set(dt: float, grid_levels: int = 5, fault_values=(0.0, 0.5, 1.0), n_vertices: int | None = None,
                     optimize: bool = False) -> tuple[CPModelSet, np.ndarray, np.ndarray]:
    """CP model set of the MSD (§3.4, (3.31)–(3.33)) on the OD run's grid; returns ``(cp, grid, vectors)``.

    ``grid`` (N_ℓ, 4) holds the large set's ``(k1, m3, f1, f2)`` and ``vectors`` its model vectors (n_q, N_ℓ).
    ``optimize`` minimises J_CP (3.29) (:func:`~fdikit.multimodel.cp_design.cp_model_set`).  Default ``False``:
    the facet-parallel enclosing simplex (J_CP = 20.4) filters better than the J_CP-optimal simplex (0.27) on
    this run — with the latter f2 reads 0.85 in its 0.5 fault and the v2 VAF falls to 76–92 % (seeds 0–2);
    six vertices (the thesis's N_h, J_CP = 0.076) leave one weight direction unidentifiable and give v2 VAF
    51–85 %.

    Parameters
    ----------
    dt : float
        Sample time [s] of the first-order discretised large set.
    grid_levels : int, default 5
        Levels of ``k1`` and ``m3`` each (>= 2).
    fault_values : sequence of float, default (0.0, 0.5, 1.0)
        Fault levels of ``f1`` and ``f2``.
    n_vertices : int, optional
        Number of simplex vertices; default the affine dimension of the set plus one.
    optimize : bool, default False
        Minimise J_CP (3.29) instead of the facet-parallel simplex.

    Returns
    -------
    cp : CPModelSet
        The vertices (``cp.models``, (n_q, N_h)) and each large-set model's convex weights.
    grid : (N_ℓ, 4) array
        The large set's parameters.
    vectors : (n_q, N_ℓ) array
        Its model vectors.

    Raises
    ------
    ParameterError
        If ``grid_levels < 2``.

    References
    ----------
    Hallouzi 2008, §3.4, (3.29), (3.31)–(3.33); §3.6.1.

    Examples
    --------
    >>> cp, grid, vectors = msd_cp_model_set(0.01, grid_levels=2)
    >>> cp.models.shape, grid.shape, vectors.shape
    ((72, 5), (20, 4), (72, 20))
    """
    grid = _grid(grid_levels, fault_values)
    vectors = msd_model_vectors(grid, dt=dt)
    return cp_model_set(vectors, n_vertices=n_vertices, optimize=optimize), grid, vectors


def msd_lv_model_set(dt: float) -> LimitValueModelSet:
    """LV model set of the MSD (§3.6.1, (3.44)–(3.49)): weights ``μ_k1, μ_m3, μ_f1, μ_f2``; "+" = k1max, m3max, 1, 1.

    Parameters
    ----------
    dt : float
        Sample time [s] of the first-order discretisation.

    Returns
    -------
    LimitValueModelSet
        The "+" model and one limit-value difference per parameter ``k1, m3, f1, f2``.

    References
    ----------
    Hallouzi 2008, §3.5; §3.6.1, (3.44)–(3.49).

    Examples
    --------
    >>> msd_lv_model_set(0.01).dt
    0.01
    """
    upper = {"k1": MSD_RANGES["k1"][1], "m3": MSD_RANGES["m3"][1], "f1": 1.0, "f2": 1.0}
    lower = {"k1": MSD_RANGES["k1"][0], "m3": MSD_RANGES["m3"][0], "f1": 0.0, "f2": 0.0}
    return limit_value_model_set(msd_matrices, upper, lower, dt=dt)


@dataclass(frozen=True)
class ModelSetRun:
    """One model set's filter run on a :class:`~fdikit.studies.hallouzi2008.msd.MSDSimulation`.

    Attributes
    ----------
    structure : {"od", "cp", "lv"}
        The model set.
    mu : (K, N) array
        Estimated weights (N = 6 for OD, the number of vertices for CP, 4 for LV).
    x : (K, 6) array
        Estimated states.
    params : (K, 4) array
        Reconstructed ``(k1, m3, f1, f2)``.
    vaf : dict of str to float
        State name → VAF (3.53) in percent.

    References
    ----------
    Hallouzi 2008, §3.6.2, Table 3.3.

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.msd import simulate_msd
    >>> run = run_msd_model_set(simulate_msd(duration=0.5, dt=0.01), "lv")
    >>> run.structure, run.mu.shape, run.params.shape
    ('lv', (50, 4), (50, 4))
    """

    structure: str
    mu: np.ndarray
    x: np.ndarray
    params: np.ndarray
    vaf: dict


def run_msd_model_set(sim: MSDSimulation, structure: str = "lv", *, q_x: float = 3e-6, q_mu: float = 1e-6,
                      grid_levels: int = 5) -> ModelSetRun:
    """Filter ``sim`` with the augmented EKF on the OD, CP or LV model set (Hallouzi 2008, §3.6.2, Table 3.3).

    Parameters
    ----------
    sim : MSDSimulation
        The run (:func:`~fdikit.studies.hallouzi2008.msd.simulate_msd`).
    structure : {"od", "cp", "lv"}, default "lv"
        Which model set.
    q_x : float, default 3e-6
        Process-noise variance per state of the filter model.
    q_mu : float, default 1e-6
        Weight random-walk variance.
    grid_levels : int, default 5
        Grid levels of the CP design (unused for OD and LV).

    Returns
    -------
    ModelSetRun
        Weights, states, reconstructed parameters and VAF per state.

    Raises
    ------
    ParameterError
        On an unknown structure.

    References
    ----------
    Hallouzi 2008, §3.6.2, Table 3.3; Table 2.3 (augmented EKF); (3.51)–(3.57) (parameter reconstruction).

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.msd import simulate_msd
    >>> run = run_msd_model_set(simulate_msd(duration=0.5, dt=0.01), "cp", grid_levels=2)
    >>> run.mu.shape
    (50, 5)
    """
    dt = float(sim.t[1] - sim.t[0])
    R = np.diag(sim.noise_std ** 2)
    x0, P0 = np.zeros(6), _P0 * np.eye(6)
    if structure == "od":
        r = run_msd_filter(sim, q_x=q_x, q_mu=q_mu)
        return ModelSetRun("od", r.mu, r.x, r.params, r.vaf)
    if structure == "cp":
        cp, grid, vectors = msd_cp_model_set(dt, grid_levels)
        mats = [unvectorize(cp.models[:, j], 6, 2, 3) for j in range(cp.models.shape[1])]
        A, B, C = (np.stack([m[i] for m in mats]) for i in range(3))
        cms = convex_model_set(A, B, C, Q=q_x * np.eye(6), R=R)
        centre = int(np.argmin(np.abs(grid - [1.0, 1.0, 1.0, 1.0]).sum(axis=1)))
        res = augmented_ekf(cms, sim.y, sim.u, x0, P0, mu0=cp.weights[:, centre], Q_mu=q_mu * np.eye(cms.N),
                            P_mu0=_P0 * np.eye(cms.N), constrain=True)
        params = grid[nearest_model(vectors, estimated_model_vector(cp.models, res.mu))]  # (3.51)–(3.52)
    elif structure == "lv":
        lv = msd_lv_model_set(dt)
        cms = limit_value_convex_set(lv, Q=q_x * np.eye(6), R=R)
        (k_lo, k_hi), (m_lo, m_hi) = MSD_RANGES["k1"], MSD_RANGES["m3"]
        mu0 = [0.5, (1 / 1.0 - 1 / m_hi) / (1 / m_lo - 1 / m_hi), 0.0, 0.0]  # k1 = m3 = 1, no fault
        res = augmented_ekf(cms, sim.y, sim.u, x0, P0, mu0=mu0, Q_mu=q_mu * np.eye(4), constrain="box")
        m = res.mu
        params = np.column_stack([lv_parameter(m[:, 0], k_hi, k_lo), lv_reciprocal_parameter(m[:, 1], m_hi, m_lo),
                                  1.0 - m[:, 2], 1.0 - m[:, 3]])  # (3.54)–(3.57)
    else:
        raise ParameterError(f"structure must be 'od', 'cp' or 'lv', got {structure!r}")
    return ModelSetRun(structure, res.mu, res.x, params, dict(zip(MSD_STATES, vaf(sim.x, res.x).tolist())))


def msd_table_3_3(sim: MSDSimulation, **kwargs) -> dict[str, ModelSetRun]:
    """Table 3.3: the three model sets on the same run (keyword arguments go to :func:`run_msd_model_set`).

    Parameters
    ----------
    sim : MSDSimulation
        The run.
    **kwargs
        Keyword arguments of :func:`run_msd_model_set` (``q_x``, ``q_mu``, ``grid_levels``).

    Returns
    -------
    dict of str to ModelSetRun
        ``"od"``, ``"cp"`` and ``"lv"`` runs.

    References
    ----------
    Hallouzi 2008, §3.6.2, Table 3.3.

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.msd import simulate_msd
    >>> list(msd_table_3_3(simulate_msd(duration=0.1, dt=0.01), grid_levels=2))
    ['od', 'cp', 'lv']
    """
    return {s: run_msd_model_set(sim, s, **kwargs) for s in ("od", "cp", "lv")}
