"""Maneuvering-target tracking: dual CMF vs augmented EKF vs IMM (Hallouzi 2008, §2.4.2, Figs 2.4–2.5).

400 samples at ``T_s = 1`` s from ``x_0 = [−500, 0, −500, 5]``; a half-acceleration left turn
``B_k = 0.5 B^(2)`` in samples [100, 150] (not in the IMM set: CM weights (0.75, 0.25)), a right turn
``B_k = B^(3)`` in [250, 300] (CM weights (0, 1)), straight flight otherwise (CM weights (0.5, 0.5)).
Interval ends are inclusive.

:func:`target_tracking_monte_carlo` runs the three filters (dual CMF λ = 0.9, EKF ``Q^μ = 1e-2 I``, IMM
with Π of (2.68)) on the same runs and returns the Monte-Carlo RMSE per sample (2.64) of position,
velocity and reconstructed B (``B̂ = Σ μ̂^(i) B^(i)``) and the mean weights.

Thesis gaps filled here (Hallouzi 2008, §2.4.2 leaves them open): the filters start from
``x̂_0 = x_0 + e``, ``e ~ N(0, R)``,
``P_0 = R``, uniform weights; the EKF weight covariance starts at ``I/12``.  The weights estimated at
sample k are compared with ``B_k``; both CM filters' μ̂_k are driven by the transition k−1 → k, a
one-sample lag that is negligible against the 51-sample maneuvers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit.errors import ParameterError
from fdikit.faults import NO_FAULT
from fdikit.gaussian import LinearGaussianModel
from fdikit.multimodel.convex import ConvexModelSet, convex_model_set
from fdikit.multimodel.convex_ekf import augmented_ekf
from fdikit.multimodel.convex_filter import dual_convex_filter
from fdikit.plants.target_tracking import (
    PI_TRACKING,
    Q_TRACKING,
    R_TRACKING,
    TRACKING_MODES,
    TS,
    X0_TRACKING,
    tracking_A,
    tracking_B,
)
from fdikit.trace import Trace

__all__ = [
    "N_SAMPLES",
    "INTERVALS",
    "maneuver_profile",
    "tracking_convex_set",
    "tracking_imm_modes",
    "target_tracking_trace",
    "TargetTrackingResult",
    "target_tracking_monte_carlo",
    "plot_target_tracking",
]

#: Run length in samples (§2.4.2).
N_SAMPLES = 400
#: Evaluation intervals (inclusive sample indices); "left_half" and "right" are the maneuvers.
INTERVALS: dict[str, tuple[int, int]] = {
    "straight_1": (0, 99),
    "left_half": (100, 150),
    "straight_2": (151, 249),
    "right": (250, 300),
    "straight_3": (301, 399),
}
_STATES = ("p_x", "v_x", "p_y", "v_y")


def tracking_convex_set(dt: float = TS) -> ConvexModelSet:
    """The two-model convex set {left turn, right turn} of §2.4.2 (``Q``, ``R`` of (2.67)).

    Parameters
    ----------
    dt : float, default TS (1.0)
        Sample time [s].

    Returns
    -------
    ConvexModelSet
        Models ``left_turn`` and ``right_turn`` (``A`` of (2.65), ``B^(2)``, ``B^(3)`` of (2.66), ``C = I_4``).

    References
    ----------
    Hallouzi 2008, §2.4.2, (2.65)–(2.67).

    Examples
    --------
    >>> ms = tracking_convex_set()
    >>> ms.names, bool(np.allclose(ms.blend([0.5, 0.5])[1], 0))
    (('left_turn', 'right_turn'), True)
    """
    B = np.stack([tracking_B("left_turn"), tracking_B("right_turn")])
    return convex_model_set(tracking_A(dt), B, np.eye(4), Q=Q_TRACKING, R=R_TRACKING,
                            names=("left_turn", "right_turn"))


def tracking_imm_modes(dt: float = TS) -> list:
    """The three IMM modes (straight, left, right) of §2.4.2 as :class:`~fdikit.gaussian.LinearGaussianModel`.

    Parameters
    ----------
    dt : float, default TS (1.0)
        Sample time [s].

    Returns
    -------
    list of LinearGaussianModel
        ``straight``, ``left_turn``, ``right_turn``, each with ``Q``, ``R`` of (2.67).

    References
    ----------
    Hallouzi 2008, §2.4.2, (2.65)–(2.68).

    Examples
    --------
    >>> [mode.name for mode in tracking_imm_modes()]
    ['straight', 'left_turn', 'right_turn']
    """
    A = tracking_A(dt)
    return [LinearGaussianModel(A=A, C=np.eye(4), Q=Q_TRACKING, R=R_TRACKING, B=tracking_B(nm), name=nm)
            for nm in TRACKING_MODES]


def maneuver_profile(n_samples: int = N_SAMPLES) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """True ``B_k`` (K, 4), convex weights (K, 2) on {left, right}, and labels (K,) of §2.4.2.

    Parameters
    ----------
    n_samples : int, default N_SAMPLES (400)
        Number of samples K.

    Returns
    -------
    B : (K, 4) array
        True input matrix per sample (``u ≡ 1``).
    mu : (K, 2) array
        True convex weights on {left, right}.
    labels : (K,) array of str
        ``"left_turn_half"``, ``"right_turn"`` or ``"none"``.

    Raises
    ------
    ParameterError
        If ``n_samples < 1``.

    References
    ----------
    Hallouzi 2008, §2.4.2.

    Examples
    --------
    >>> B, mu, lab = maneuver_profile()
    >>> mu[[0, 100, 150, 151, 250]].tolist(), str(lab[120])
    ([[0.5, 0.5], [0.75, 0.25], [0.75, 0.25], [0.5, 0.5], [0.0, 1.0]], 'left_turn_half')
    """
    if n_samples < 1:
        raise ParameterError(f"n_samples must be positive, got {n_samples}")
    k = np.arange(n_samples)
    mu = np.full((n_samples, 2), 0.5)
    labels = np.full(n_samples, NO_FAULT, dtype=object)
    left = (k >= 100) & (k <= 150)
    right = (k >= 250) & (k <= 300)
    mu[left] = (0.75, 0.25)
    mu[right] = (0.0, 1.0)
    labels[left], labels[right] = "left_turn_half", "right_turn"
    Bs = np.stack([tracking_B("left_turn").ravel(), tracking_B("right_turn").ravel()])
    return mu @ Bs, mu, labels.astype(str)


def target_tracking_trace(seed=None, n_samples: int = N_SAMPLES) -> Trace:
    """One simulated run (Hallouzi 2008, §2.4.2): ``x_{k+1} = A x_k + B_k u_k + w_k``, ``y_k = x_k + v_k``, ``u ≡ 1``.

    ``seed`` is an int or a ``numpy.random.Generator``.  Labels: ``left_turn_half``, ``right_turn``, ``none``.

    Parameters
    ----------
    seed : int or numpy.random.Generator, optional
        Source of the process and measurement noise.
    n_samples : int, default N_SAMPLES (400)
        Number of samples.

    Returns
    -------
    Trace
        Control ``u``; outputs ``p_x_meas, v_x_meas, p_y_meas, v_y_meas``; states ``p_x, v_x, p_y, v_y``;
        fault labels of :func:`maneuver_profile`.

    References
    ----------
    Hallouzi 2008, §2.4.2, (2.65)–(2.67).

    Examples
    --------
    >>> tr = target_tracking_trace(0, n_samples=20)
    >>> tr.y.shape, tr.outputs[0]
    ((20, 4), 'p_x_meas')
    """
    rng = np.random.default_rng(seed)
    B, mu, labels = maneuver_profile(n_samples)
    A = tracking_A(TS)
    Lq, Lr = np.linalg.cholesky(Q_TRACKING), np.linalg.cholesky(R_TRACKING)
    w = rng.standard_normal((n_samples, 4)) @ Lq.T
    v = rng.standard_normal((n_samples, 4)) @ Lr.T
    x = np.empty((n_samples, 4))
    x[0] = X0_TRACKING
    for k in range(n_samples - 1):
        x[k + 1] = A @ x[k] + B[k] + w[k]
    return Trace(t=TS * np.arange(n_samples), u=np.ones((n_samples, 1)), y=x + v, controls=("u",),
                 outputs=tuple(f"{s}_meas" for s in _STATES), x=x, states=_STATES, fault=labels,
                 meta={"plant": "target_tracking", "source": "Hallouzi 2008, §2.4.2"})


@dataclass(frozen=True)
class TargetTrackingResult:
    """Monte-Carlo comparison of §2.4.2 (Figs 2.4–2.5).

    Attributes
    ----------
    t : (K,) array
        Sample times [s].
    filters : tuple of str
        Filter names (``"dual_cmf"``, ``"ekf"``, ``"imm"``).
    rmse_position, rmse_velocity, rmse_B : dict of str to (K,) array
        Filter → RMSE (2.64) per sample over the runs ([m], [m/s], and of B̂).
    mean_weights : dict of str to (K, N) array
        Filter → weights averaged over the runs (IMM: its 3 mode probabilities).
    cm_weights : dict of str to (K, 2) array
        Filter → mean weights in CM coordinates (left, right); for the IMM
        ``μ_left = 0.5 + (μ^(2) − μ^(3))/2``, which reconstructs the same B̂.
    chatter : dict of str to float
        Filter → mean over runs and samples in [100, 150] of ``|Δμ_left|`` per sample.
    summary : dict
        Filter → interval of :data:`INTERVALS` → {"position", "velocity", "B"} mean RMSE over the interval.
    true_weights : (K, 2) array
        True CM weights (:func:`maneuver_profile`).
    runs : int
        Number of Monte-Carlo runs.
    seed : int or None
        Master seed.

    References
    ----------
    Hallouzi 2008, §2.4.2, Figs 2.4–2.5, (2.64).

    Examples
    --------
    >>> result = target_tracking_monte_carlo(runs=1, n_samples=160, filters=("ekf",))
    >>> result.rmse_position["ekf"].shape, list(result.summary["ekf"])
    ((160,), ['straight_1', 'left_half'])
    """

    t: np.ndarray
    filters: tuple[str, ...]
    rmse_position: dict
    rmse_velocity: dict
    rmse_B: dict
    mean_weights: dict
    cm_weights: dict
    chatter: dict
    summary: dict
    true_weights: np.ndarray
    runs: int
    seed: int | None


#: At most this many runs per resumable part of :func:`target_tracking_monte_carlo` (a part holds the sums
#: of its runs); fewer when that gives less than four parts, so that short runs resume in steps too.
CHUNK_RUNS = 10


def _chunk_sums(children, filters, lam, q_mu, n_samples) -> dict:
    """Sums over the runs seeded by ``children`` of the squared errors, weights and chatter of each filter."""
    ms = tracking_convex_set(TS)
    B_true, _, _ = maneuver_profile(n_samples)
    B_cm = ms.B[:, :, 0]  # (2, 4)
    B_imm = np.stack([tracking_B(nm).ravel() for nm in ("straight", "left_turn", "right_turn")])
    if "imm" in filters:
        from fdikit.multimodel.imm import IMMFilter

        modes = tracking_imm_modes(TS)
    se = {f: {q: np.zeros(n_samples) for q in ("pos", "vel", "B")} for f in filters}
    wsum = {f: np.zeros((n_samples, 3 if f == "imm" else 2)) for f in filters}
    chat = {f: 0.0 for f in filters}
    lo, hi = INTERVALS["left_half"]
    Lr = np.linalg.cholesky(R_TRACKING)
    for child in children:
        rng = np.random.default_rng(child)
        tr = target_tracking_trace(rng, n_samples)
        x0 = tr.x[0] + Lr @ rng.standard_normal(4)
        for f in filters:
            if f == "dual_cmf":
                r = dual_convex_filter(ms, tr.y, tr.u, x0, R_TRACKING, lam=lam)
                xh, mu, Bh = r.x, r.mu, r.mu @ B_cm
                left = mu[:, 0]
            elif f == "ekf":
                r = augmented_ekf(ms, tr.y, tr.u, x0, R_TRACKING, Q_mu=q_mu * np.eye(2))
                xh, mu, Bh = r.x, r.mu, r.mu @ B_cm
                left = mu[:, 0]
            else:
                r = IMMFilter(modes, PI_TRACKING, x0=x0, P0=R_TRACKING).run(tr.u, tr.y)
                xh, mu, Bh = r.x, r.mu, r.mu @ B_imm
                left = 0.5 + 0.5 * (mu[:, 1] - mu[:, 2])
            err = tr.x - xh
            se[f]["pos"] += err[:, 0] ** 2 + err[:, 2] ** 2
            se[f]["vel"] += err[:, 1] ** 2 + err[:, 3] ** 2
            se[f]["B"] += ((Bh - B_true) ** 2).sum(axis=1)
            wsum[f] += mu
            chat[f] += np.abs(np.diff(left[lo:hi + 1])).mean()
    return {f: {"pos": se[f]["pos"].tolist(), "vel": se[f]["vel"].tolist(), "B": se[f]["B"].tolist(),
                "w": wsum[f].tolist(), "chatter": chat[f]} for f in filters}


def target_tracking_monte_carlo(runs: int = 100, seed: int | None = 0, *, lam: float = 0.9, q_mu: float = 1e-2,
                                filters=("dual_cmf", "ekf", "imm"), n_samples: int = N_SAMPLES, store=None,
                                progress=None) -> TargetTrackingResult:
    """Monte-Carlo comparison of the dual CMF, the augmented EKF and the IMM (Hallouzi 2008, §2.4.2).

    Parameters
    ----------
    runs : int, default 100
        Number of runs (thesis: 100).
    seed : int or None, default 0
        Master seed (runs use ``SeedSequence(seed).spawn``).
    lam : float, default 0.9
        Dual-CMF forgetting factor (thesis 0.9).
    q_mu : float, default 1e-2
        EKF ``Q^μ = q_mu I`` (thesis 1e-2).
    filters : sequence of str, default ("dual_cmf", "ekf", "imm")
        Subset of ``("dual_cmf", "ekf", "imm")``.
    n_samples : int, default N_SAMPLES (400)
        Samples per run; intervals of :data:`INTERVALS` beyond the run are left out of ``summary``.
    store : :class:`fdikit.resume.RunStore`, optional
        Keeps the sums of every chunk of runs (``min(CHUNK_RUNS, max(1, runs // 4))`` runs) as a part as
        soon as they are complete and reuses the parts already there, so a killed run resumes.  The runs
        are always summed chunk by chunk in chunk order, so the result is the same bit for bit with or
        without a store and however often the run was interrupted.
    progress : callable, optional
        Called with the number of runs done after each chunk.

    Returns
    -------
    TargetTrackingResult
        RMSE per sample, mean weights, chatter and per-interval summary of each filter.

    Raises
    ------
    ParameterError
        For unknown filters or fewer than one run.

    References
    ----------
    Hallouzi 2008, §2.4.2, Figs 2.4–2.5, (2.64), (2.68); Tables 2.2–2.3 (dual CMF, augmented EKF).

    Examples
    --------
    >>> result = target_tracking_monte_carlo(runs=1, n_samples=160, filters=("imm",))
    >>> result.mean_weights["imm"].shape, result.cm_weights["imm"].shape
    ((160, 3), (160, 2))
    """
    filters = tuple(filters)
    bad = set(filters) - {"dual_cmf", "ekf", "imm"}
    if bad or not filters:
        raise ParameterError(f"unknown filters {sorted(bad)}; choose from 'dual_cmf', 'ekf', 'imm'")
    if isinstance(runs, bool) or not isinstance(runs, int | np.integer) or runs < 1:
        raise ParameterError(f"runs must be an integer of at least 1, got {runs!r}")
    _, mu_true, _ = maneuver_profile(n_samples)
    children = np.random.SeedSequence(seed).spawn(runs)
    se = {f: {q: np.zeros(n_samples) for q in ("pos", "vel", "B")} for f in filters}
    wsum = {f: np.zeros((n_samples, 3 if f == "imm" else 2)) for f in filters}
    chat = {f: 0.0 for f in filters}
    chunk = min(CHUNK_RUNS, max(1, runs // 4))
    for start in range(0, runs, chunk):
        key = f"runs-{start:05d}"
        part = None if store is None else store.load(key)
        if part is None:
            part = _chunk_sums(children[start:start + chunk], filters, lam, q_mu, n_samples)
            if store is not None:
                part = store.save(key, part)
        for f in filters:
            for q in ("pos", "vel", "B"):
                se[f][q] += np.asarray(part[f][q], dtype=float)
            wsum[f] += np.asarray(part[f]["w"], dtype=float)
            chat[f] += float(part[f]["chatter"])
        if progress is not None:
            progress(min(start + chunk, runs))
    rmse = {q: {f: np.sqrt(se[f][q] / runs) for f in filters} for q in ("pos", "vel", "B")}
    mean_w = {f: wsum[f] / runs for f in filters}
    cm_w = {f: (np.column_stack([0.5 + 0.5 * (w[:, 1] - w[:, 2]), 0.5 - 0.5 * (w[:, 1] - w[:, 2])])
                if f == "imm" else w) for f, w in mean_w.items()}
    summary = {f: {name: {"position": float(rmse["pos"][f][a:b + 1].mean()),
                          "velocity": float(rmse["vel"][f][a:b + 1].mean()),
                          "B": float(rmse["B"][f][a:b + 1].mean())}
                   for name, (a, b) in INTERVALS.items() if b < n_samples}
               for f in filters}
    return TargetTrackingResult(t=TS * np.arange(n_samples), filters=filters, rmse_position=rmse["pos"],
                                rmse_velocity=rmse["vel"], rmse_B=rmse["B"], mean_weights=mean_w,
                                cm_weights=cm_w, chatter={f: c / runs for f, c in chat.items()},
                                summary=summary, true_weights=mu_true, runs=runs, seed=seed)


def plot_target_tracking(result: TargetTrackingResult, path=None, axes=None):
    """Figs 2.4–2.5 style plot (position, velocity and B RMSE, mean left-turn weight), into ``axes`` or to ``path``.

    ``path`` is written atomically (:func:`fdikit.plots.save_figure`); a binary file object also works.

    Parameters
    ----------
    result : TargetTrackingResult
        From :func:`target_tracking_monte_carlo`.
    path : str, PathLike or binary file object, optional
        Where the PNG goes.
    axes : sequence of four matplotlib Axes, optional
        The position, velocity, B and weight panels; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure or the given ``axes``
        A new figure (closed once written to ``path``) when ``axes`` is None, else ``axes``.

    References
    ----------
    Hallouzi 2008, §2.4.2, Figs 2.4–2.5.

    Examples
    --------
    Drawing the four panels takes over a second, so it is not run here:

    >>> import io
    >>> buffer = io.BytesIO()
    >>> plot_target_tracking(target_tracking_monte_carlo(runs=1, n_samples=160), buffer)  # doctest: +SKIP
    >>> buffer.getvalue()[1:4]  # doctest: +SKIP
    b'PNG'
    """
    from fdikit.plots import axes_or_new, finish_plot

    fig, panes = axes_or_new(axes, 4, figsize=(8, 10), sharex=True)
    panels = (("position RMSE [m]", result.rmse_position), ("velocity RMSE [m/s]", result.rmse_velocity),
              ("B reconstruction RMSE [-]", result.rmse_B))
    for ax, (label, data) in zip(panes, panels):
        for f in result.filters:
            ax.plot(result.t, data[f], label=f, lw=1)
        ax.set_ylabel(label)
    for f in result.filters:
        panes[3].plot(result.t, result.cm_weights[f][:, 0], label=f, lw=1)
    panes[3].plot(result.t, result.true_weights[:, 0], "k--", label="true", lw=1)
    panes[3].set_ylabel("mean μ_left (CM coord.)")
    panes[3].set_xlabel("sample k")
    for ax in panes:
        for name in ("left_half", "right"):
            a, b = INTERVALS[name]
            ax.axvspan(result.t[0] + a * TS, result.t[0] + b * TS, color="0.9")
        ax.legend(fontsize=7, loc="upper right")
    panes[0].set_title(f"Hallouzi 2008 §2.4.2, {result.runs} Monte-Carlo runs")
    return finish_plot(fig, axes, path)
