"""Varga (2017), Chapter 8: the aircraft case studies CS1 (flight actuator faults) and CS2 (air data sensor faults).

The data are the reference's (``Examples/cs1data.jld2``, ``cs2data.jld2`` of FaultDetectionTools.jl, MIT licence,
shipped in ``fdikit/studies/varga2017/data``): eleven linearised longitudinal–lateral models of a civil aircraft
for mass variations, model 7 (index 6 here) nominal; for CS1 also the actuator model ``ACT`` (22 actuators) and the
output-feedback gain ``K`` of the flight controller (``u = K y + v``).

* CS1 (§8.1): eight primary actuator faults (four ailerons, two elevators, the stabiliser, the rudder) enter as
  additive faults of the actuator commands; three wind inputs are disturbances.  A bank of six least-order filters
  (``efdisyn``, strong detection of constant faults) for the reference's structure matrix ``SFDI``, or, with the
  measured surface positions (CS1_2), eight filters for ``I₈``.  Tables 8.2/8.3 are the closed-loop robustness of the
  nominal bank on every model: ``‖R_u‖∞``, ``‖R_d‖∞``, ``‖R_f − R̃_f‖∞``.
* CS2 (§8.2): additive faults of the angle-of-attack and calibrated-airspeed sensors.  Constant (order 0) filters
  per model (Table 8.4: ``N_ref``, ``N_nom``, ``N_0``, and ``N_opt`` of a constant gain tuned over all models by
  Nelder–Mead) and the mass-scheduled gains of Remark 8.1 interpolated by polynomials of degree 0–4 (Table 8.5).

The interconnections (series with the actuators, positive output feedback on selected channels, residual of the
filter on the closed loop) are written here in numpy, as the reference's scripts write them with DescriptorSystems.jl
operations.

References
----------
Varga (2017), §8.1 (CS1, Tables 8.2–8.3), §8.2 (CS2, Tables 8.4–8.5, Remark 8.1); fdtools (``Examples/CS1_1.jl``,
``CS1_2.jl``, ``CS2_1.jl``, ``CS2_2.jl`` and their ``@test`` lines).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = [
    "ACTUATOR_FAULTS", "CS1_SFDI", "NOMINAL", "SENSOR_FAULTS", "AircraftCase", "data_file", "actuator_case",
    "sensor_case", "positive_feedback", "closed_loop_norms", "closed_loop_degree", "static_gain_error",
    "remark81_gains", "interpolated_gain_errors",
]

#: Index of the nominal model (the reference's ``nom = 7``).
NOMINAL = 6
#: The primary actuators (the reference's ``act_prim = [1,2,15,16,17,19,18,20]``, 1-based).
ACTUATOR_FAULTS = ("aileron_1", "aileron_2", "aileron_3", "aileron_4", "elevator_1", "elevator_2", "stabilizer",
                   "rudder")
_ACT_PRIM = (0, 1, 14, 15, 16, 18, 17, 19)
#: The air data sensors with faults (the reference's ``sen = [2, 4]``).
SENSOR_FAULTS = ("angle_of_attack", "calibrated_airspeed")
_SEN = (1, 3)
#: CS1_1's structure matrix for the isolation of single actuator faults (columns ``ACTUATOR_FAULTS``).
CS1_SFDI = np.array([[0, 1, 1, 1, 1, 0, 1, 0],
                     [1, 0, 1, 1, 0, 1, 1, 0],
                     [1, 1, 0, 1, 1, 0, 1, 0],
                     [1, 1, 1, 0, 1, 1, 0, 0],
                     [1, 1, 1, 1, 0, 0, 0, 0],
                     [0, 0, 0, 0, 0, 0, 0, 1]], dtype=bool)


def data_file(case: str) -> Path:
    """The shipped reference data of case study ``"cs1"`` or ``"cs2"``.

    Parameters
    ----------
    case : {"cs1", "cs2"}
        The case study.

    Returns
    -------
    Path
        The ``.jld2`` file.

    Raises
    ------
    ParameterError
        Another case name.

    Examples
    --------
    >>> data_file("cs2").name
    'cs2data.jld2'

    References
    ----------
    fdtools (``Examples/cs1data.jld2``, ``cs2data.jld2``).
    """
    if case not in ("cs1", "cs2"):
        raise ParameterError(f"case must be 'cs1' or 'cs2', got {case!r}")
    return Path(str(resources.files("fdikit.studies.varga2017") / "data" / f"{case}data.jld2"))


@dataclass(frozen=True, eq=False)
class AircraftCase:
    """The synthesis models of one case study and what its assessment needs.

    Attributes
    ----------
    models : tuple of FaultModel
        One per mass case (controls ``u``, disturbances ``d``, faults ``f``); ``models[NOMINAL]`` is nominal.
    extended : tuple of tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``[G_u G_d G_f; I 0 0]`` per model: the signals ``[y; u]`` a filter reads.
    K : numpy.ndarray or None
        The output-feedback gain (CS1), ``u = K y_fb + v``.
    feedback_outputs : tuple of int
        Rows of ``y`` fed back through ``K`` (CS1_2: the original measurements after the surface positions).
    mass : numpy.ndarray or None
        The normalised mass of each model, 0 … 1 (CS2's ``massi``).

    Examples
    --------
    >>> case = sensor_case()
    >>> len(case.models), case.models[NOMINAL].faults
    (11, ('angle_of_attack', 'calibrated_airspeed'))

    References
    ----------
    Varga (2017), §8.1–8.2.
    """

    models: tuple[FaultModel, ...]
    extended: tuple[tuple[np.ndarray, ...], ...]
    K: np.ndarray | None
    feedback_outputs: tuple[int, ...]
    mass: np.ndarray | None


def _extended(model: FaultModel) -> tuple[np.ndarray, ...]:
    """``[G; [I 0 0]]``: the outputs ``y`` and the controls ``u`` as functions of ``(u, d, f)``."""
    mu, m = len(model.controls), model.B.shape[1]
    Iu = np.eye(mu, m)
    return model.A, model.B, np.vstack([model.C, np.zeros((mu, model.n))]), np.vstack([model.D, Iu])


def _fault_model(A, B, C, D, mu: int, md: int, faults, names) -> FaultModel:
    """``fdimodset``: controls ``B[:, :mu]``, disturbances the next ``md`` columns, faults the given columns."""
    c, d, f = list(range(mu)), list(range(mu, mu + md)), list(faults)
    return FaultModel(A, C, Bu=B[:, c], Du=D[:, c], Bd=B[:, d], Dd=D[:, d], Bf=B[:, f], Df=D[:, f], faults=names)


def actuator_case(*, positions: bool = False) -> AircraftCase:
    """CS1: the aircraft with its actuators, primary actuator faults and the flight controller's gain.

    Parameters
    ----------
    positions : bool, default False
        False: the measurements of the aircraft only (CS1_1).  True: the eight primary surface positions are
        measured too, as the first outputs (CS1_2).

    Returns
    -------
    AircraftCase
        Models of order 32 or less (aircraft 10 + actuators 22, made minimal like the reference's ``gir``).

    Examples
    --------
    >>> case = actuator_case()
    >>> m = case.models[NOMINAL]
    >>> len(m.controls), len(m.disturbances), len(m.faults), len(m.outputs)
    (22, 3, 8, 10)

    References
    ----------
    Varga (2017), §8.1; fdtools (``Examples/CS1_1.jl``, ``CS1_2.jl``, Part 1).
    """
    from fdikit.descriptor.jld2 import read_jld2
    from fdikit.descriptor.model import DescriptorModel
    from fdikit.descriptor.reduction import minimal_realization

    data = read_jld2(data_file("cs1"), ["SYSACM", "K", "ACT"])
    act, K = data["ACT"], data["K"]
    mu = act.C.shape[0]
    models, extended = [], []
    for ac in data["SYSACM"]:
        m = ac.D.shape[1]
        md = m - mu
        # aircraft * append(ACT, I_md): the actuators drive the first mu inputs, the winds pass through
        na = act.n
        Ca = np.vstack([act.C, np.zeros((md, na))])
        Da = np.block([[act.D, np.zeros((mu, md))], [np.zeros((md, mu)), np.eye(md)]])
        Ba = np.hstack([act.B, np.zeros((na, md))])
        A = np.block([[ac.A, ac.B @ Ca], [np.zeros((na, ac.n)), act.A]])
        B = np.vstack([ac.B @ Da, Ba])
        C = np.hstack([ac.C, ac.D @ Ca])
        D = ac.D @ Da
        if positions:
            sel = np.eye(m)[list(_ACT_PRIM)]
            C = np.vstack([np.hstack([np.zeros((len(_ACT_PRIM), ac.n)), sel @ Ca]), C])
            D = np.vstack([sel @ Da, D])
        red = minimal_realization(DescriptorModel(A, C, Bu=B, Du=D))
        model = _fault_model(red.A, red.B, red.C, red.D, mu, md, _ACT_PRIM, ACTUATOR_FAULTS)
        models.append(model)
        extended.append(_extended(model))
    p = data["SYSACM"][0].C.shape[0]
    off = len(_ACT_PRIM) if positions else 0
    return AircraftCase(tuple(models), tuple(extended), K, tuple(range(off, off + p)), None)


def sensor_case() -> AircraftCase:
    """CS2: the aircraft models with additive faults of the angle-of-attack and calibrated-airspeed sensors.

    Returns
    -------
    AircraftCase
        Eleven models (the last two inputs are the wind disturbances) and the mass variations.

    Examples
    --------
    >>> sensor_case().mass.round(1).tolist()[:3]
    [0.0, 0.1, 0.2]

    References
    ----------
    Varga (2017), §8.2; fdtools (``Examples/CS2_1.jl``, Part 1).
    """
    from fdikit.descriptor.jld2 import read_jld2

    data = read_jld2(data_file("cs2"), ["SYSACSM", "massi"])
    models, extended = [], []
    for ac in data["SYSACSM"]:
        p, m = ac.D.shape
        md = 2
        sen = np.eye(p)[:, list(_SEN)]
        B = np.hstack([ac.B, np.zeros((ac.n, len(_SEN)))])
        D = np.hstack([ac.D, sen])
        model = _fault_model(ac.A, B, ac.C, D, m - md, md, range(m, m + len(_SEN)), SENSOR_FAULTS)
        models.append(model)
        extended.append(_extended(model))
    return AircraftCase(tuple(models), tuple(extended), None, (), np.asarray(data["massi"], float).ravel())


def positive_feedback(A, B, C, D, K, inputs, outputs) -> tuple[np.ndarray, ...]:
    """Close ``u[inputs] = K y[outputs] + v`` around ``(A, B, C, D)``, keeping every input and output.

    Parameters
    ----------
    A, B, C, D : array_like
        The open loop.
    K : array_like
        ``(len(inputs), len(outputs))`` gain.
    inputs, outputs : sequence of int
        The fed-back input and measured output indices.

    Returns
    -------
    tuple of numpy.ndarray
        ``(A, B, C, D)`` of the closed loop from ``v`` (in place of the fed-back inputs) and the other inputs.

    Raises
    ------
    ParameterError
        ``K`` of the wrong shape, or an algebraic loop ``I − K D_{yu}`` that is singular.

    Examples
    --------
    ``x' = u``, ``y = x`` with ``u = −2 y + v``: the closed-loop pole is −2.

    >>> positive_feedback([[0.0]], [[1.0]], [[1.0]], [[0.0]], [[-2.0]], [0], [0])[0].tolist()
    [[-2.0]]

    References
    ----------
    Varga (2017), §8.1 (the closed-loop assessment; DescriptorSystems' ``feedback(…; negative = false)``).
    """
    A, B, C, D, K = (np.atleast_2d(np.asarray(x, float)) for x in (A, B, C, D, K))
    iu, iy = list(inputs), list(outputs)
    if K.shape != (len(iu), len(iy)):
        raise ParameterError(f"K must be {len(iu)}x{len(iy)} (fed-back inputs x measured outputs), got {K.shape}")
    Dyu = D[np.ix_(iy, iu)]
    L = np.eye(len(iu)) - K @ Dyu
    if np.linalg.cond(L) > 1e12:
        raise ParameterError("the loop u = K y + v is algebraic and I − K D_yu is singular; it cannot be closed")
    Bu, Du = B[:, iu], D[:, iu]
    Bo, Do = B.copy(), D.copy()
    Bo[:, iu], Do[:, iu] = 0.0, 0.0
    # u[iu] = v + K (C_y x + D_yu u[iu] + D_y,others w)  ⇒  u[iu] = Fx x + Fin (v, w), with L = I − K D_yu
    Fx = np.linalg.solve(L, K @ C[iy])
    Fin = np.linalg.solve(L, _selector(iu, B.shape[1]) + K @ Do[iy])
    return A + Bu @ Fx, Bo + Bu @ Fin, C + Du @ Fx, Do + Du @ Fin


def _selector(rows, m: int) -> np.ndarray:
    S = np.zeros((len(rows), m))
    S[range(len(rows)), list(rows)] = 1.0
    return S


def _hinf(A, B, C, D) -> float:
    """‖C (sI − A)⁻¹ B + D‖∞ of a stable realisation, computed on it as it is (AB13DD through python-control).

    No minimal realisation first: the channels assessed here are stable by construction, and removing nearly
    uncontrollable modes of a near-cancelled channel (a decoupled ``R_d``) at the usual tolerance 1e-7 perturbs
    what is left — on CS1's nominal closed loop it turned ‖R_d‖∞ ≈ 1e-7 into 9e-3.
    """
    import control

    from fdikit.analysis.channels import HINF_TOL

    if A.shape[0] and np.linalg.eigvals(A).real.max() >= 0:
        raise ParameterError("the assessed channel is unstable; the filter or the closed loop is not stable")
    if not A.shape[0]:
        return float(np.linalg.norm(D, 2))
    return float(control.linfnorm(control.ss(A, B, C, D), tol=HINF_TOL)[0])


def _reader(generator, model: FaultModel) -> tuple[np.ndarray, ...]:
    """The filter's ``(A, B, C, D)`` with its input columns in the order ``[y; u]`` of ``model`` (zero if unread)."""
    signals = list(model.outputs) + list(model.controls)
    reads = list(generator.controls) + list(generator.outputs)
    unknown = [s for s in reads if s not in signals]
    if unknown:
        raise ParameterError(f"the filter reads {unknown}, which the model has not; design it on this model")
    P = np.zeros((len(reads), len(signals)))
    P[range(len(reads)), [signals.index(s) for s in reads]] = 1.0
    return generator.A, generator.B @ P, generator.C, generator.D @ P


def closed_loop_degree(case: AircraftCase) -> float:
    """The largest real part of the closed-loop poles over the models (CS1's ``sdeg_cloop``, at least −5).

    Parameters
    ----------
    case : AircraftCase
        A CS1 case (with ``K``).

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        A case without a controller gain.

    Examples
    --------
    >>> closed_loop_degree(actuator_case()) < 0
    True

    References
    ----------
    Varga (2017), §8.1; fdtools (``Examples/CS1_1.jl``, ``sdeg_cloop``).
    """
    if case.K is None:
        raise ParameterError("the case has no controller gain K (only CS1 does)")
    worst = -5.0
    for m in case.models:
        A = positive_feedback(m.A, m.B, m.C, m.D, case.K, range(len(m.controls)), case.feedback_outputs)[0]
        worst = max(worst, float(np.linalg.eigvals(A).real.max()))
    return worst


def closed_loop_norms(case: AircraftCase, generator) -> np.ndarray:
    """Tables 8.2/8.3: ``‖R_u‖∞``, ``‖R_d‖∞`` and ``‖R_f − R̃_f‖∞`` of a filter on every closed-loop model.

    ``R = Q · [G_u G_d G_f; I 0 0]`` closed with ``u = K y + v`` (``R_u`` from ``v``), and ``R̃_f`` the filter's
    fault response on the nominal open loop.

    Parameters
    ----------
    case : AircraftCase
        A CS1 case.
    generator : ResidualGenerator
        The filter (or stacked bank) designed on ``case.models[NOMINAL]``.

    Returns
    -------
    numpy.ndarray
        ``(len(case.models), 3)``.

    Raises
    ------
    ParameterError
        A case without ``K``, or a filter reading signals the models lack.

    Examples
    --------
    >>> from fdikit.design.nullspace import efdisyn
    >>> case = actuator_case(positions=True)
    >>> bank = efdisyn(case.models[NOMINAL], np.eye(8), fdtol=1e-5, fdgaintol=0.01, fdfreq=0, sdeg=-5.0)
    >>> bool(closed_loop_norms(case, bank.generator)[NOMINAL].max() < 1e-6)
    True

    References
    ----------
    Varga (2017), §8.1, Tables 8.2 and 8.3; fdtools (``Examples/CS1_1.jl``, Part 4).
    """
    from fdikit.design.nullspace.factorization import series

    if case.K is None:
        raise ParameterError("the case has no controller gain K (only CS1 does)")
    nom = case.models[NOMINAL]
    Q = _reader(generator, nom)
    mu, md = len(nom.controls), len(nom.disturbances)
    cols = {"u": slice(0, mu), "d": slice(mu, mu + md), "f": slice(mu + md, None)}
    # R̃_f on the nominal open loop: the actuator faults enter as the commands u_j do (B_f, D_f are columns of
    # B_u, D_u), and Q decouples u exactly, so Q_y G_f = −Q_u[:, j]: a stable realisation with the filter's poles
    ju = [len(nom.outputs) + nom.controls.index(c) for c in _fault_commands(nom)]   # u_j among Q's [y; u] inputs
    A0, B0, C0, D0 = Q[0], -Q[1][:, ju], Q[2], -Q[3][:, ju]
    out = np.zeros((len(case.models), 3))
    for i, ext in enumerate(case.extended):
        cl = positive_feedback(*ext, case.K, range(mu), case.feedback_outputs)
        A, B, C, D = series(cl, Q)
        out[i, 0] = _hinf(A, B[:, cols["u"]], C, D[:, cols["u"]])
        out[i, 1] = _hinf(A, B[:, cols["d"]], C, D[:, cols["d"]])
        n, n0 = A.shape[0], A0.shape[0]
        Ad = np.block([[A, np.zeros((n, n0))], [np.zeros((n0, n)), A0]])
        out[i, 2] = _hinf(Ad, np.vstack([B[:, cols["f"]], B0]), np.hstack([C, -C0]), D[:, cols["f"]] - D0)
    return out


def _fault_commands(model: FaultModel) -> list[str]:
    """The control inputs whose columns the fault inputs repeat (CS1's actuator faults), in fault order."""
    mu = len(model.controls)
    Bu, Du = model.B[:, :mu], model.D[:, :mu]
    Bf, Df = model.B[:, -len(model.faults):], model.D[:, -len(model.faults):]
    out = []
    for j in range(len(model.faults)):
        hit = [i for i in range(mu) if np.array_equal(Bu[:, i], Bf[:, j]) and np.array_equal(Du[:, i], Df[:, j])]
        if not hit:
            raise ParameterError(f"fault {model.faults[j]!r} is not an actuator fault (no control column equals it)")
        out.append(model.controls[hit[0]])
    return out


def static_gain_error(case: AircraftCase, gain, models=None) -> np.ndarray:
    """CS2's ``‖D [G_u G_d G_f; I 0 0] − [0 0 I]‖∞`` of a constant filter ``D`` (columns ``[y; u]``) per model.

    Parameters
    ----------
    case : AircraftCase
        The CS2 case.
    gain : array_like
        One ``(mf, p + mu)`` gain for every model, or ``(N, mf, p + mu)``: model ``i`` gets ``gain[i]``.
    models : sequence of int, optional
        The models to assess (default all).

    Returns
    -------
    numpy.ndarray
        One norm per model assessed.

    Raises
    ------
    ParameterError
        A gain of the wrong shape.

    Examples
    --------
    The Remark 8.1 gains decouple exactly, model by model:

    >>> case = sensor_case()
    >>> bool(static_gain_error(case, remark81_gains(case)).max() < 1e-7)
    True

    References
    ----------
    Varga (2017), §8.2, Table 8.4; fdtools (``Examples/CS2_1.jl``, Parts 4–7).
    """
    idx = range(len(case.models)) if models is None else list(models)
    G = np.asarray(gain, dtype=float)
    out = []
    for i in idx:
        A, B, C, D = case.extended[i]
        Di = G if G.ndim == 2 else G[i]
        mf = len(case.models[i].faults)
        if Di.shape != (mf, C.shape[0]):
            raise ParameterError(f"the gain must be {mf}x{C.shape[0]} (faults x [y; u]), got {Di.shape}")
        ref = np.hstack([np.zeros((mf, B.shape[1] - mf)), np.eye(mf)])
        out.append(_hinf(A, B, Di @ C, Di @ D - ref))
    return np.array(out)


def remark81_gains(case: AircraftCase) -> np.ndarray:
    """The constant gains of Remark 8.1: ``D_i [C_i D_i] = [0 0 0 I]`` solved for each model, ``(N, mf, p + mu)``.

    Parameters
    ----------
    case : AircraftCase
        The CS2 case.

    Returns
    -------
    numpy.ndarray

    Examples
    --------
    >>> remark81_gains(sensor_case()).shape
    (11, 2, 11)

    References
    ----------
    Varga (2017), §8.2, Remark 8.1; fdtools (``Examples/CS2_2.jl``, Part 3: ``Dref / [C D]``).
    """
    out = []
    for model, (_A, _B, C, D) in zip(case.models, case.extended):
        mf = len(model.faults)
        cde = np.hstack([C, D])
        ref = np.hstack([np.zeros((mf, cde.shape[1] - mf)), np.eye(mf)])
        out.append(np.linalg.lstsq(cde.T, ref.T, rcond=None)[0].T)
    return np.array(out)


def interpolated_gain_errors(case: AircraftCase, maxdeg: int = 4) -> np.ndarray:
    """Table 8.5: the error of the Remark 8.1 gains interpolated in the mass by polynomials of degree 0…``maxdeg``.

    Every gain entry is fitted by least squares over the eleven mass values (``Polynomials.fit``); column ``k`` is
    the error ``‖D_k(m_i) [G; I 0 0] − [0 0 I]‖∞`` of the degree-``k`` fit on model ``i``.

    Parameters
    ----------
    case : AircraftCase
        The CS2 case.
    maxdeg : int, default 4
        The highest degree.

    Returns
    -------
    numpy.ndarray
        ``(len(case.models), maxdeg + 1)``.

    Raises
    ------
    ParameterError
        ``maxdeg`` negative or not below the number of models.

    Examples
    --------
    >>> interpolated_gain_errors(sensor_case(), 0).shape
    (11, 1)

    References
    ----------
    Varga (2017), §8.2, Table 8.5; fdtools (``Examples/CS2_2.jl``).
    """
    N = len(case.models)
    if not 0 <= maxdeg < N:
        raise ParameterError(f"maxdeg must be 0 … {N - 1} (fewer than the {N} models), got {maxdeg}")
    gains = remark81_gains(case)
    flat = gains.reshape(N, -1)
    out = np.zeros((N, maxdeg + 1))
    for deg in range(maxdeg + 1):
        coef = np.polynomial.polynomial.polyfit(case.mass, flat, deg)
        fitted = np.polynomial.polynomial.polyval(case.mass, coef).T.reshape(gains.shape)
        out[:, deg] = static_gain_error(case, fitted)
    return out
