"""B747 linear simulation with model set I: augmented EKF weights (Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3).

The eight JSBSim local models of model set I (Table 4.3,
:func:`~fdikit.studies.hallouzi2008.aircraft_models.model_set`) are blended by the augmented EKF of §2.3.3
(:func:`~fdikit.multimodel.convex_ekf.augmented_ekf`), which estimates the ten states and the eight weights
of a linear jump simulation of the fault scenario of Table 4.6 (interval ends as printed, [s]):

=====================  ===========  =========================================================
fault                  interval     plant simulated in the interval
=====================  ===========  =========================================================
elevators at 10 deg    15–20        LIP model at +10 deg (``local_model(ac, "elevator", 10)``)
α sensor 50 %          35–40        ``local_model(ac, "alpha_sensor", 0.5)`` (α row of C × 0.5)
rudders at −15 deg     52.5–60      LIP model at −15 deg
hydraulic #4 outage    75–80        model 7 of set I
engine separation      95–end       model 5 of set I
=====================  ===========  =========================================================

and the nominal model (8) elsewhere.  Every model is the affine discrete model of
:meth:`~fdikit.studies.hallouzi2008.aircraft_models.LocalModel.discrete` (App. B, first order, ``T = 0.01`` s) in
absolute coordinates, ``x⁺ = A_d x + B_d u + c_d + w``, ``y = C x + v``; at a switch the state carries over.

Choices made here where the thesis gives none (all stated):

* **Noise** (4.3)–(4.4), converted from deg, deg/s to rad, rad/s (factor ``(π/180)²`` on the angle and rate
  entries; V [m/s] and h [m] unchanged).  ``Q_s`` has only eight printed entries for ten states; β and φ take
  1e-4 deg² like the other angles.  ``Q_s`` is read as a continuous-time intensity, discretised to first order
  (App. B) as the per-sample ``Q = Q_s T``; ``R = R_s`` per sample.  Taken per sample instead, V would random-walk
  by 3 m/s in one second (σ = 0.32 m/s every 10 ms), and then (measured, seed 0, same tuning) the nominal
  weight stays at 0.6–0.8 in the fault-free intervals and the VAF of the bank angle falls to 70 %.
* **Controller**: continuous LQR on the nominal ``(A, B)`` (the fault models are unstable, so a closed loop
  is needed), Bryson's rule ``Q = diag(1/x_max²)``, ``R = diag(1/u_max²)`` with ``x_max`` = 5 deg/s (p, q, r),
  5 m/s (V), 2 deg (α, β), 5 deg (φ, θ), 10 deg (ψ), 10 m (h) and ``u_max`` = 15 deg (aileron), 20 deg
  (elevator, rudder), 5 deg (stabiliser, a slow trim surface), 100 kN (thrust); sampled every ``T`` on the
  *true* state, ``u_k = sat(u° − K (x_k − x°) + e_k)`` with the nominal trim ``(x°, u°)`` and the surface
  commands saturated at the App. A limits of :data:`fdikit.aircraft.actuators.B747_LIMITS` (aileron ±20,
  elevator −23…17, rudder ±25, stabiliser −12…3 deg).  The affine offsets
  ``c_d`` of a fault model make the loop settle at a new equilibrium (no integral action); during the locks the
  loop drives the dead surface's command into its limit.
* **Excitation** ``e_k``: low-pass white noise (first order, τ = 1 s), 1 deg std, on the aileron, elevator and
  rudder commands, so that the surfaces whose effectiveness the faults change move (the thesis does not
  describe its inputs).
* **EKF**: ``Q``, ``R`` of the simulation, ``Q^μ = 1e-4 I`` per sample, ``P^μ_0 = I/12``, prior the nominal
  trim with ``P_0 = 100 Q``, ``μ_0`` = nominal, and the covariance-weighted simplex projection of
  :func:`~fdikit.multimodel.convex_ekf.augmented_ekf` (``projection="covariance"``).  With the thesis's
  Euclidean projection (P unchanged) the same run loses V and h (VAF 0 %).

A LIP model at ``δ`` is (to first order) affine in ``δ``: ``c(δ) ≈ c(0) + b_δ δ`` with the surface's column
``b_δ`` zero.  The blend ``μ M_17 + (1 − μ) M_nom`` of the 17-deg model and the nominal one then acts as a
surface at ``17 μ + (1 − μ) u_δ`` with ``u_δ`` the commanded deflection, so it reproduces a lock at 10 deg for
``μ = (10 − u_δ)/(17 − u_δ)``: 10/17 ≈ 0.59 only if the controller leaves the command at zero.
:func:`equivalent_lip_weight` gives this weight from the simulated commands.

References
----------
Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3, (4.3)–(4.4); §4.3.2–§4.3.3, Table 4.3 (model set I); §2.3.3,
Table 2.3 (augmented EKF); §4.4.2, Table 4.7 (the isolation logic); (3.53) (VAF); App. A (surface limits);
App. B (discretisation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError

__all__ = [
    "T_S", "NOMINAL", "DURATION", "SCENARIO", "Q_S_THESIS", "R_S_THESIS", "Table46Scenario", "Table46Result",
    "noise_covariances", "b747_lqr_gain", "build_table_4_6", "simulate_table_4_6", "run_table_4_6",
    "equivalent_lip_weight", "model_set_i_logic", "table_4_6_isolation", "scenario_intervals",
]

#: Sample time [s] (100 Hz, §4.4.1).
T_S = 0.01
#: Run length [s] (the engine separation from 95 s is kept for 20 s).
DURATION = 115.0
#: 0-based index of the nominal model in model set I.
NOMINAL = 7
#: Table 4.6: (label, truth, start [s], end [s]); truth is (fault, size) for ``local_model`` or a set-I index.
SCENARIO = (
    ("elevator", ("elevator", 10.0), 15.0, 20.0),
    ("alpha_sensor", ("alpha_sensor", 0.5), 35.0, 40.0),
    ("rudder", ("rudder", -15.0), 52.5, 60.0),
    ("hydraulic", 6, 75.0, 80.0),
    ("engine", 4, 95.0, np.inf),
)
#: (4.3), thesis units (deg, deg/s, m/s, m) for p q r V α β φ θ ψ h; β and φ (not printed) as the other angles.
Q_S_THESIS = np.array([1e-8, 1e-8, 1e-8, 1e-1, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-1])
#: (4.4), thesis units, for the measured p q r V α θ ψ h ("realistic B747 sensor covariances" in the thesis).
R_S_THESIS = np.array([1.73e-4, 1.73e-4, 1.73e-4, 1e-1, 1.73e-4, 1.73e-4, 1.73e-4, 1e-1])
_ANGLE_STATES = np.array([1, 1, 1, 0, 1, 1, 1, 1, 1, 0], bool)
_ANGLE_MEASURED = np.array([1, 1, 1, 0, 1, 1, 1, 0], bool)
_X_MAX = np.array([5.0, 5.0, 5.0, 5.0, 2.0, 2.0, 5.0, 5.0, 10.0, 10.0])   # deg, deg/s except V [m/s], h [m]
_U_MAX = np.array([15.0, 20.0, 5.0, 20.0, 1e5])                             # deg except thrust [N]
_EXCITE_STD = np.radians(1.0)
_EXCITE_TAU = 1.0
_Q_MU = 1e-4
_PROJECTION = "covariance"
_GROUPS = {"rudder": (0, 1), "elevator": (2, 3), "engine": (4,), "alpha_sensor": (5,), "hydraulic": (6,)}


def noise_covariances(dt: float = T_S) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample ``Q = Q_s T`` (10 x 10) and ``R = R_s`` (8 x 8) of (4.3)–(4.4) in SI units (rad, rad/s, m/s, m).

    Parameters
    ----------
    dt : float, optional
        Sample time ``T`` [s]; ``Q_s`` is read as a continuous-time intensity (module docstring).

    Returns
    -------
    Q, R : ndarray
        Diagonal covariances; the angle and rate entries of the thesis's deg values times ``(π/180)²``.

    Raises
    ------
    ParameterError
        If ``dt`` is not positive.

    Examples
    --------
    >>> Q, R = noise_covariances()
    >>> float(Q[3, 3]), bool(np.isclose(R[0, 0], 1.73e-4 * (np.pi / 180) ** 2))
    (0.001, True)

    References
    ----------
    Hallouzi 2008, §4.4.1, (4.3)–(4.4); App. B.
    """
    dt = validate.positive("dt", dt)
    d2r = (np.pi / 180.0) ** 2
    return (np.diag(np.where(_ANGLE_STATES, Q_S_THESIS * d2r, Q_S_THESIS)) * dt,
            np.diag(np.where(_ANGLE_MEASURED, R_S_THESIS * d2r, R_S_THESIS)))


def b747_lqr_gain(nominal) -> np.ndarray:
    """Continuous LQR gain ``K`` (5 x 10) on the nominal model, Bryson's rule weights (module docstring).

    Parameters
    ----------
    nominal : LocalModel
        The nominal model of :func:`~fdikit.studies.hallouzi2008.aircraft_models.b747_at_point`.

    Returns
    -------
    ndarray
        ``u = u° − K (x − x°)``.

    Examples
    --------
    >>> from fdikit.studies.hallouzi2008.aircraft_models import b747_at_point
    >>> _, nominal = b747_at_point()
    >>> K = b747_lqr_gain(nominal)
    >>> m = nominal.linearization.model
    >>> K.shape, bool(np.linalg.eigvals(m.A - m.B @ K).real.max() < 0)
    ((5, 10), True)

    References
    ----------
    Hallouzi 2008, §4.4.1 (an LQ controller because the fault models are unstable).
    """
    from fdikit.aircraft.autopilot import lqr_autopilot
    from fdikit.aircraft.plant import STATES

    m = nominal.linearization.model
    xmax = np.where(_ANGLE_STATES, np.radians(_X_MAX), _X_MAX)
    umax = np.concatenate([np.radians(_U_MAX[:4]), _U_MAX[4:]])
    return lqr_autopilot(nominal.linearization, dict(zip(STATES, xmax, strict=True)),
                         dict(zip(m.controls, umax, strict=True)), inputs=m.controls).K


@dataclass(frozen=True)
class Table46Scenario:
    """The model set, the plants of the fault intervals, the controller and the noise of §4.4.1.

    Attributes
    ----------
    models : tuple of LocalModel
        Model set I (Table 4.3), model 8 nominal.
    truths : dict of str to LocalModel
        Plant per scenario label (:data:`SCENARIO`) and ``"nominal"``.
    K : ndarray
        LQR gain (5 x 10), :func:`b747_lqr_gain`.
    x_trim, u_trim : ndarray
        The nominal trim ``x°`` (10), ``u°`` (5) the controller regulates to.
    Q, R : ndarray
        :func:`noise_covariances`.
    dt : float
        Sample time [s].

    Examples
    --------
    >>> scenario = build_table_4_6()  # doctest: +SKIP
    >>> len(scenario.models)  # doctest: +SKIP
    8

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """

    models: tuple
    truths: dict
    K: np.ndarray
    x_trim: np.ndarray
    u_trim: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    dt: float = T_S


@dataclass(frozen=True)
class Table46Result:
    """One run of the §4.4.1 scenario.

    Attributes
    ----------
    t : ndarray
        Sample times (K,) [s].
    labels : ndarray of str
        True fault per sample: ``"none"`` or a :data:`SCENARIO` label.
    true_mu : ndarray
        (K, 8) weights of the simulated plant in model set I; for the LIP intervals the weights of a lock
        affine in its position with the command at zero (10/17 on model 3, 15/25 on model 2, rest nominal).
    mu : ndarray
        (K, 8) weights estimated by the augmented EKF.
    x, x_hat : ndarray
        (K, 10) true and estimated states (SI).
    u : ndarray
        (K, 5) inputs applied (commands after saturation).
    vaf : dict of str to float
        State name → VAF (3.53) of ``x_hat`` against ``x`` over the run [%].

    Examples
    --------
    >>> res = run_table_4_6(seed=1, duration=2.0)  # doctest: +SKIP
    >>> res.mu.shape  # doctest: +SKIP
    (200, 8)

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """

    t: np.ndarray
    labels: np.ndarray
    true_mu: np.ndarray
    mu: np.ndarray
    x: np.ndarray
    x_hat: np.ndarray
    u: np.ndarray
    vaf: dict


def build_table_4_6(aircraft=None, nominal=None) -> Table46Scenario:
    """Build model set I, the fault plants of Table 4.6 and the LQR from JSBSim's B747.

    Parameters
    ----------
    aircraft, nominal : optional
        From :func:`~fdikit.studies.hallouzi2008.aircraft_models.b747_at_point` (built when omitted; both or
        neither).

    Returns
    -------
    Table46Scenario

    Raises
    ------
    ParameterError
        If only one of ``aircraft`` and ``nominal`` is given.

    Examples
    --------
    >>> sc = build_table_4_6()
    >>> [m.name for m in sc.models][:3], sorted(sc.truths)[:3]
    (['rudder_lip_+25', 'rudder_lip_-25', 'elevator_lip_+17'], ['alpha_sensor', 'elevator', 'engine'])

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """
    from fdikit.studies.hallouzi2008.aircraft_models import b747_at_point, local_model, model_set

    if (aircraft is None) != (nominal is None):
        raise ParameterError("pass both aircraft and nominal (from b747_at_point()) or neither")
    if aircraft is None:
        aircraft, nominal = b747_at_point(T_S)
    models = tuple(model_set(aircraft, nominal, "I"))
    snap = aircraft.snapshot()
    truths = {"nominal": models[NOMINAL]}
    for label, truth, _, _ in SCENARIO:
        truths[label] = models[truth] if isinstance(truth, int) else local_model(aircraft, *truth, nominal=nominal)
    aircraft.restore(snap)
    lin = nominal.linearization
    Q, R = noise_covariances()
    return Table46Scenario(models, truths, b747_lqr_gain(nominal), lin.x0.copy(), lin.u0.copy(), Q, R)


def _schedule(t: np.ndarray) -> np.ndarray:
    labels = np.full(t.size, "none", dtype=object)
    for label, _, start, end in SCENARIO:
        labels[(t >= start - 1e-9) & (t < end - 1e-9)] = label
    return labels


def _true_weights(labels: np.ndarray) -> np.ndarray:
    mu = np.zeros((labels.size, 8))
    mu[:, NOMINAL] = 1.0
    table = {"elevator": {2: 10 / 17, NOMINAL: 7 / 17}, "rudder": {1: 15 / 25, NOMINAL: 10 / 25},
             "alpha_sensor": {5: 0.5, NOMINAL: 0.5}, "hydraulic": {6: 1.0, NOMINAL: 0.0},
             "engine": {4: 1.0, NOMINAL: 0.0}}
    for label, weights in table.items():
        rows = labels == label
        for i, w in weights.items():
            mu[rows, i] = w
    return mu


def simulate_table_4_6(scenario: Table46Scenario, seed=None, duration: float = DURATION) -> dict:
    """The linear jump simulation of Table 4.6 in closed loop (module docstring).

    Parameters
    ----------
    scenario : Table46Scenario
    seed : int or numpy.random.Generator, optional
        Process, measurement and excitation noise.
    duration : float, optional
        Run length [s] (default :data:`DURATION`).

    Returns
    -------
    dict
        ``t`` (K,), ``labels`` (K,), ``x`` (K, 10), ``u`` (K, 5) and ``y`` (K, 8); ``u[k]`` acts on
        ``x[k] → x[k+1]``.

    Raises
    ------
    ParameterError
        If ``duration`` is not positive.

    Examples
    --------
    >>> sim = simulate_table_4_6(build_table_4_6(), seed=1, duration=1.0)
    >>> sim["x"].shape, sim["y"].shape
    ((100, 10), (100, 8))

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """
    from fdikit.aircraft.actuators import B747_LIMITS

    validate.positive("duration", duration)
    surfaces = ("aileron", "elevator", "stabilizer", "rudder")
    low = np.array([B747_LIMITS[s].lower for s in surfaces] + [-np.inf])
    high = np.array([B747_LIMITS[s].upper for s in surfaces] + [np.inf])
    rng = np.random.default_rng(seed)
    dt = scenario.dt
    n_steps = int(round(duration / dt))
    t = np.arange(n_steps) * dt
    labels = _schedule(t)
    disc = {k: m.discrete(dt) for k, m in scenario.truths.items()}
    Lq, Lr = np.sqrt(np.diag(scenario.Q)), np.sqrt(np.diag(scenario.R))
    a = np.exp(-dt / _EXCITE_TAU)
    excite = np.zeros(5)
    x = scenario.x_trim.copy()
    xs, us, ys = np.zeros((n_steps, 10)), np.zeros((n_steps, 5)), np.zeros((n_steps, 8))
    for k in range(n_steps):
        Ad, Bd, C = disc["nominal" if labels[k] == "none" else labels[k]]
        u = np.clip(scenario.u_trim - scenario.K @ (x - scenario.x_trim) + excite, low, high)
        xs[k], us[k] = x, u
        ys[k] = C @ x + Lr * rng.standard_normal(8)
        x = Ad @ x + Bd[:, :5] @ u + Bd[:, 5] + Lq * rng.standard_normal(10)
        excite[[0, 1, 3]] = a * excite[[0, 1, 3]] + np.sqrt(1 - a * a) * _EXCITE_STD * rng.standard_normal(3)
    return {"t": t, "labels": labels.astype(str), "x": xs, "u": us, "y": ys}


def run_table_4_6(scenario: Table46Scenario | None = None, seed=0, duration: float = DURATION,
                  q_mu: float = _Q_MU, projection: str = _PROJECTION) -> Table46Result:
    """Simulate Table 4.6 and run the augmented EKF with model set I (Hallouzi 2008, §4.4.1, Fig. 4.3).

    Parameters
    ----------
    scenario : Table46Scenario, optional
        From :func:`build_table_4_6` (built when omitted).
    seed : int or numpy.random.Generator, optional
        Noise seed (default 0).
    duration : float, optional
        Run length [s].
    q_mu : float, optional
        ``Q^μ = q_mu I`` per sample (default 1e-4).
    projection : {"covariance", "euclidean"}, optional
        Simplex projection of the EKF (default ``"covariance"``, module docstring).

    Returns
    -------
    Table46Result

    Raises
    ------
    ParameterError
        If ``q_mu`` or ``duration`` is not positive, or ``projection`` is unknown.

    Examples
    --------
    >>> res = run_table_4_6(seed=1, duration=2.0)
    >>> res.mu.shape, bool(res.mu[-1, 7] > 0.8)
    ((200, 8), True)

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """
    from fdikit.aircraft.plant import STATES
    from fdikit.metrics import vaf
    from fdikit.multimodel.convex import convex_model_set
    from fdikit.multimodel.convex_ekf import augmented_ekf

    validate.positive("q_mu", q_mu)
    validate.choice("projection", projection, ("covariance", "euclidean"))
    scenario = build_table_4_6() if scenario is None else scenario
    sim = simulate_table_4_6(scenario, seed, duration)
    disc = [m.discrete(scenario.dt) for m in scenario.models]
    cms = convex_model_set(np.stack([d[0] for d in disc]), np.stack([d[1] for d in disc]),
                           np.stack([d[2] for d in disc]), Q=scenario.Q, R=scenario.R,
                           names=[m.name for m in scenario.models])
    u_aug = np.column_stack([sim["u"], np.ones(sim["t"].size)])
    mu0 = np.zeros(8)
    mu0[NOMINAL] = 1.0
    res = augmented_ekf(cms, sim["y"], u_aug, x0=scenario.x_trim, P0=100.0 * scenario.Q, mu0=mu0,
                        Q_mu=q_mu * np.eye(8), projection=projection)
    labels = sim["labels"]
    return Table46Result(sim["t"], labels, _true_weights(labels), res.mu, sim["x"], res.x, sim["u"],
                         dict(zip(STATES, map(float, vaf(sim["x"], res.x)))))


def scenario_intervals(t) -> list[tuple[str, float, float]]:
    """The fault intervals of :data:`SCENARIO` and the fault-free ones between them (``"none_1"``, …).

    Parameters
    ----------
    t : ndarray
        Sample times of a run [s].

    Returns
    -------
    list of (name, start, end)

    Examples
    --------
    >>> [name for name, _, _ in scenario_intervals(np.arange(0.0, 45.0, 0.01))]
    ['none_1', 'elevator', 'none_2', 'alpha_sensor', 'none_3']

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6.
    """
    out, last, i = [], 0.0, 1
    end_t = float(t[-1]) + (t[1] - t[0] if t.size > 1 else T_S)
    for label, _, start, end in SCENARIO:
        if start >= end_t:
            break
        if start > last:
            out.append((f"none_{i}", last, start))
            i += 1
        out.append((label, start, min(end, end_t)))
        last = min(end, end_t)
    if last < end_t:
        out.append((f"none_{i}", last, end_t))
    return out


def equivalent_lip_weight(result: Table46Result, label: str) -> float:
    """Weight of the set-I LIP model that reproduces a simulated lock, ``(δ − ū)/(δ_i − ū)``.

    A LIP model is (to first order) affine in its lock position, so ``μ M_i + (1 − μ) M_nom`` acts as the

    Parameters
    ----------
    result : Table46Result
    label : {"elevator", "rudder"}
        The LIP interval: elevator at 10 deg against model 3 (17 deg), rudder at −15 deg against model 2
        (−25 deg).

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        For another label, or a run that does not reach the interval.

    Examples
    --------
    >>> r = Table46Result(np.array([0.0, 1.0]), np.array(["elevator"] * 2), None, None, None, None,
    ...                   np.zeros((2, 5)), {})
    >>> round(equivalent_lip_weight(r, "elevator"), 3)
    0.588

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """
    validate.choice("label", label, ("elevator", "rudder"))
    lock, model, col = (10.0, 17.0, 1) if label == "elevator" else (-15.0, -25.0, 3)
    rows = result.labels == label
    if not rows.any():
        raise ParameterError(f"the run has no {label!r} interval; simulate at least {DURATION} s")
    ubar = float(np.degrees(result.u[rows, col].mean()))
    return (lock - ubar) / (model - ubar)


def model_set_i_logic(threshold: float = 0.2):
    """Table 4.7 logic for model set I: rudder (1, 2), elevator (3, 4), engine (5), α sensor (6), hydraulic (7).

    Parameters
    ----------
    threshold : float, optional
        ``T_f`` (default 0.2).

    Returns
    -------
    GroupThresholdLogic
        0-based groups; nominal model index 7.

    Examples
    --------
    >>> logic = model_set_i_logic()
    >>> logic.isolate([[0, 0, 0, 0, 0, 0.5, 0, 0.5], [0, 0, 0, 0, 0, 0, 0, 1]]).tolist()
    ['alpha_sensor', 'none']

    References
    ----------
    Hallouzi 2008, §4.4.2, Table 4.7 (groups adapted to model set I, Table 4.3).
    """
    from fdikit.multimodel.isolation import GroupThresholdLogic

    return GroupThresholdLogic(groups=_GROUPS, nominal=NOMINAL, threshold=threshold)


def table_4_6_isolation(result: Table46Result, threshold: float = 0.2, settle: float = 1.0) -> dict:
    """What :func:`model_set_i_logic` declares in each interval of the run.

    Parameters
    ----------
    result : Table46Result
    threshold : float, optional
        ``T_f`` (default 0.2).
    settle : float, optional
        Seconds skipped at the start of every interval (the weights' transient; default 1).

    Returns
    -------
    dict
        Interval name (a :data:`SCENARIO` label or ``"none_1"``, …) → ``(declared, fraction)``: the most
        frequent decision after ``settle`` and the fraction of those samples that it holds.

    Raises
    ------
    ParameterError
        If ``settle`` is negative.

    Examples
    --------
    >>> t = np.arange(300) * 0.01
    >>> mu = np.tile(np.eye(8)[7], (300, 1))
    >>> r = Table46Result(t, np.array(["none"] * 300), mu, mu, None, None, None, {})
    >>> table_4_6_isolation(r)
    {'none_1': ('none', 1.0)}

    References
    ----------
    Hallouzi 2008, §4.4.1, Table 4.6, Fig. 4.3.
    """
    settle = validate.non_negative("settle", settle)
    decided = model_set_i_logic(threshold).isolate(result.mu)
    out = {}
    for name, start, end in scenario_intervals(result.t):
        rows = (result.t >= start + settle - 1e-9) & (result.t < end - 1e-9)
        if not rows.any():
            continue
        names, counts = np.unique(decided[rows], return_counts=True)
        best = int(np.argmax(counts))
        out[name] = (str(names[best]), float(counts[best] / rows.sum()))
    return out
