"""Observer-based residual generators: pole placement and the steady-state Kalman filter.

The residual is the output estimation error (innovation) of a full-order observer
(Douglas et al. 1996, Ch. 3, eq. (3.2))::

    x̂' = A x̂ + Bu u + L (y − C x̂ − Du u)
    r   = y − C x̂ − Du u

so that, with ``e = x − x̂``, ``e' = (A − L C) e + (Bf − L Df) f + …`` and ``r = C e + Df f + …``.
The report writes ``r = C x̂ + D u − y``, the negative of this; fdikit uses the
innovation sign so that a positive sensor bias gives a positive residual.

In discrete time the observer is in predictor form (``x̂[k+1|k]``), which makes the
Kalman residual the white innovation sequence with covariance ``C P Cᵀ + R``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from fdikit import lti, validate
from fdikit.design.labels import label_generator
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = ["ObserverDesign", "observer", "kalman", "observer_generator", "unobservable_modes"]


@dataclass(frozen=True, eq=False)
class ObserverDesign(FieldReport):
    """Result of an observer design.

    Attributes
    ----------
    generator : ResidualGenerator
        The residual generator (residual names = output names).
    gain : (n, p) array
        Observer gain ``L`` (python-control's ``lqe`` sign: the filter's state matrix is ``A − L C``).
    poles : (n,) complex array
        Eigenvalues of ``A − L C``.
    covariance : (n, n) array or None
        Steady-state estimation-error covariance ``P`` (Kalman only).
    innovation_covariance : (p, p) array or None
        Covariance of the residual in steady state (Kalman only; ``C P Cᵀ + R`` in discrete time,
        ``R`` — the white-noise intensity — in continuous time).
    model : FaultModel or None
        The model the design was made for (keyword-only; set by the design function).

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> from fdikit.design import observer
    >>> d = observer(FaultModel(A=[[0, 1], [-2, -3]], C=[[1, 0]], Bu=[[0], [1]]), poles=[-5, -6])
    >>> d.gain.ravel().round(6).tolist(), d.generator.residuals, d.covariance is None
    ([8.0, 4.0], ('y0',), True)

    References
    ----------
    Douglas et al. 1996, Ch. 3, (3.2) (the observer; the report writes ``A + L C``, i.e. ``−gain``).
    """

    generator: ResidualGenerator
    gain: np.ndarray
    poles: np.ndarray
    covariance: np.ndarray | None = None
    innovation_covariance: np.ndarray | None = None
    def report(self) -> dict:
        """``gain`` (``L``), ``poles`` (of ``A − L C``), ``covariance`` (``P``) and ``innovation_covariance``.

        The two covariances are None for a pole-placement design.
        """
        return {"gain": self.gain, "poles": self.poles, "covariance": self.covariance,
                "innovation_covariance": self.innovation_covariance}


def unobservable_modes(A: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Eigenvalues λ of ``A`` with ``rank [A − λI; C] < n`` (PBH test, scale-aware tolerance).

    Parameters
    ----------
    A : (n, n) array_like
        State matrix.
    C : (p, n) array_like
        Output matrix.

    Returns
    -------
    (k,) complex array
        The unobservable eigenvalues of ``(C, A)`` (empty when the pair is observable).

    Examples
    --------
    >>> unobservable_modes([[-1.0, 0.0], [0.0, -2.0]], [[1.0, 0.0]]).real.tolist()
    [-2.0]

    References
    ----------
    Douglas et al. 1996, Ch. 3 (a stable observer detects every fault when ``(C, A)`` is observable).
    """
    A = validate.as_square("A", A)
    n = A.shape[0]
    C = validate.as_matrix("C", C, (None, n))
    scale = max(np.linalg.norm(A, 2), np.linalg.norm(C, 2), 1.0)
    out = []
    for lam in scipy.linalg.eigvals(A):
        s = np.linalg.svd(np.vstack([A - lam * np.eye(n), C]), compute_uv=False)
        if s[-1] <= 1e3 * np.finfo(float).eps * n * scale:
            out.append(lam)
    return np.array(out)


def observer_generator(
    model: FaultModel,
    L: np.ndarray,
    outputs: Sequence[str] | None = None,
    projection: np.ndarray | None = None,
    isolates: Sequence[str | None] | Mapping[str, str | None] | None = None,
    *,
    names: Sequence[str] | None = None,
) -> ResidualGenerator:
    """The residual generator of the observer ``x̂' = A x̂ + Bu u + L (y − C x̂ − Du u)``.

    The residual is ``r = y − C x̂ − Du u``, or its coordinates ``Qᵀ r`` in the columns of an
    output ``projection`` Q (p x k; e.g. the projected residuals of a detection filter).

    Parameters
    ----------
    model : FaultModel
        The plant (continuous or discrete); the generator reads its controls and outputs.
    L : (n, p) array_like
        Observer gain (the filter's state matrix is ``A − L C``).
    outputs : sequence of str, optional
        Names of the residuals (default: the model's output names, or ``r0, r1 …`` with a projection); the
        same as ``names``.
    projection : (p, k) array_like, optional
        Output projection ``Q``; the residuals are ``Qᵀ r`` (default: identity, all ``p`` residuals).
    isolates : sequence of (str or None) or mapping, optional
        The fault each residual isolates, by fault name: one entry per residual (None: detection only), or a
        mapping residual name -> fault (:func:`~fdikit.design.labels.residual_labels`); default none.
    names : sequence of str, optional
        Residual names (the keyword all designs take; give ``names`` or ``outputs``, not both).

    Returns
    -------
    ResidualGenerator
        ``z' = (A − L C) z + [Bu − L Du, L] [u; y]``, ``r = Qᵀ (y − C z − Du u)``; it carries the model's
        operating point, when the model has one.

    Raises
    ------
    ParameterError
        A bad gain or projection shape, both ``outputs`` and ``names``, or bad ``names`` / ``isolates``.
    ModelError
        An ``isolates`` entry that is no fault of the model.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=[[0, 1], [-2, -3]], C=[[1, 0]], Bu=[[0], [1]])
    >>> g = observer_generator(m, [[9.0], [4.0]])
    >>> g.residuals, g.A.tolist()
    (('y0',), [[-9.0, 1.0], [-6.0, -3.0]])

    References
    ----------
    Douglas et al. 1996, Ch. 3, (3.2) (with the innovation sign ``r = y − ŷ``).
    """
    validate.instance("model", model, FaultModel)
    A, C, Bu, Du = model.A, model.C, model.Bu, model.Du
    L = validate.as_matrix("L (the observer gain)", L, (model.n, model.p))
    Q = np.eye(model.p) if projection is None else validate.as_matrix("projection", projection, (model.p, None))
    if outputs is not None and names is not None:
        raise ParameterError("give the residual names once: names= (outputs= is its older spelling)")
    outputs = names if outputs is None else outputs
    if outputs is None:
        outputs = model.outputs if projection is None else tuple(f"r{k}" for k in range(Q.shape[1]))
    outputs = (outputs,) if isinstance(outputs, str) else tuple(outputs)
    if len(outputs) != Q.shape[1]:
        raise ParameterError(f"{len(outputs)} residual names for {Q.shape[1]} residuals")
    gen = ResidualGenerator(
        A=A - L @ C,
        B=np.hstack([Bu - L @ Du, L]),
        C=-Q.T @ C,
        D=np.hstack([-Q.T @ Du, Q.T]),
        controls=model.controls,
        outputs=model.outputs,
        residuals=tuple(outputs),
        dt=model.dt,
    )
    return label_generator(gen, model, None, isolates)


def _check_stable(model: FaultModel, poles: np.ndarray, what: str) -> None:
    bad = ~lti.is_stable(poles, model.is_discrete)
    if np.any(bad):
        modes = unobservable_modes(model.A, model.C)
        raise DesignError(
            f"{what} is not stable: poles {np.round(poles[bad], 6).tolist()}"
            + (f"; the model has unobservable modes {np.round(modes, 6).tolist()} that no gain can move" if modes.size
               else "")
        )


def observer(model: FaultModel, poles: Sequence[complex], method: str = "place", *, names: Sequence[str] | None = None,
             isolates: Sequence[str | None] | Mapping[str, str | None] | None = None) -> ObserverDesign:
    """Full-order observer residual generator by pole placement.

    Parameters
    ----------
    model : FaultModel (continuous or discrete)
    poles : n desired eigenvalues of ``A − L C`` (complex values in conjugate pairs).
    method : ``'place'`` (:func:`control.place`, Tits–Yang; repeated poles up to the
        number of outputs) or ``'varga'`` (:func:`control.place_varga`, Schur method).
    names, isolates : optional
        Residual names (default the output names) and the fault each residual isolates (default none), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    ObserverDesign
        Generator, gain ``L``, the attained poles; ``covariance`` and ``innovation_covariance`` are None.

    Raises
    ------
    ParameterError
        When ``model`` is not a FaultModel, ``poles`` is not ``n`` finite values, or ``method`` is unknown.
    ------
    DesignError
        When the pair (C, A) is not observable (the unobservable modes are named), the
        requested poles cannot be placed, or the placed observer is not stable.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit import FaultModel
    >>> from fdikit.design import observer
    >>> m = FaultModel(A=[[0, 1], [-2, -3]], C=[[1, 0]], Bu=[[0], [1]])
    >>> d = observer(m, poles=[-5, -6])
    >>> np.sort(d.poles.real)
    array([-6., -5.])

    References
    ----------
    Douglas et al. 1996, Ch. 3, (3.2).
    """
    import control

    validate.instance("model", model, FaultModel)
    poles = _poles(poles, model.n)
    validate.choice("placement method", method, ("place", "varga"))
    fn = {"place": control.place, "varga": control.place_varga}[method]
    modes = unobservable_modes(model.A, model.C)
    if modes.size:
        raise DesignError(
            f"(C, A) is not observable: modes {np.round(modes, 6).tolist()} do not reach the outputs; "
            "pole placement needs every mode observable (use kalman() for a detectable model)"
        )
    try:
        L = np.asarray(fn(model.A.T, model.C.T, poles)).T
    except Exception as exc:  # python-control/slycot raise assorted types
        raise DesignError(f"pole placement failed for poles {poles.tolist()}: {exc}") from exc
    achieved = scipy.linalg.eigvals(model.A - L @ model.C)
    _check_stable(model, achieved, "the placed observer")
    return ObserverDesign(observer_generator(model, L, isolates=isolates, names=names), L, achieved, model=model)


def _poles(poles, n: int) -> np.ndarray:
    """``n`` finite poles as a complex vector (ParameterError otherwise)."""
    out = validate.as_complex_vector("poles", poles)
    if out.shape != (n,):
        raise ParameterError(f"need {n} observer poles (one per state), got {out.size}")
    return out


def kalman(model: FaultModel, Q, R, *, names: Sequence[str] | None = None,
           isolates: Sequence[str | None] | Mapping[str, str | None] | None = None) -> ObserverDesign:
    """Steady-state Kalman filter residual generator (the innovation).

    The Riccati equation is solved by :func:`scipy.linalg.solve_discrete_are` or
    :func:`scipy.linalg.solve_continuous_are` in its filtering form, with the
    cross-covariance ``S = Bw Q Dwᵀ`` when the noise also reaches the outputs.
    Discrete gain (predictor form): ``L = (A P Cᵀ + S)(C P Cᵀ + R̄)⁻¹``; continuous:
    ``L = (P Cᵀ + S) R̄⁻¹`` with ``R̄ = R + Dw Q Dwᵀ``.

    Parameters
    ----------
    model : FaultModel
        Process noise enters through the noise group ``w`` (``Bw``, ``Dw``); a model
        without a noise group takes ``Q`` as the covariance of noise added to every state.
    Q : float or (k, k) array_like
        Covariance of ``w`` (k = number of noise inputs, or n state noises), per sample in discrete
        time, intensity (PSD) in continuous time; a scalar means ``Q I``.
    R : float or (p, p) array_like
        Covariance (intensity) of measurement noise added to every output; a scalar means ``R I``.
    names, isolates : optional
        Residual names (default the output names) and the fault each residual isolates (default none: the
        innovation detects; ``isolates=["yaw_rate_sensor", …]`` ties each output's residual to a fault), as
        :func:`~fdikit.design.labels.residual_labels`.

    Returns
    -------
    ObserverDesign
        Generator, gain ``L``, poles of ``A − L C``, ``covariance`` ``P`` and ``innovation_covariance``.

    Raises
    ------
    ParameterError
        When ``model`` is not a FaultModel, or ``Q`` or ``R`` is not a symmetric positive semidefinite
        matrix of the right size.
    DesignError
        When the Riccati equation has no stabilising solution (e.g. an undetectable mode).

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> m = FaultModel(A=[[0, 1], [-2, -3]], C=[[1, 0]], Bu=[[0], [1]])
    >>> k = kalman(m, Q=1.0, R=0.1)
    >>> k.gain.ravel().round(6).tolist(), k.innovation_covariance.tolist()
    ([2.94946, -0.650342], [[0.1]])

    References
    ----------
    Hallouzi 2008, §2.3.1, Table 2.1 step 2 (the Kalman cycle; here its steady state).
    """
    validate.instance("model", model, FaultModel)
    n, p = model.n, model.p
    if model.noise:
        G, H = model.Bw, model.Dw
        Q = validate.as_covariance("Q", Q, len(model.noise))
    else:
        G, H = np.eye(n), np.zeros((p, n))
        Q = validate.as_covariance("Q", Q, n)
    R = validate.as_covariance("R", R, p)
    Qx, Rbar, S = G @ Q @ G.T, R + H @ Q @ H.T, G @ Q @ H.T
    A, C = model.A, model.C
    try:
        if model.is_discrete:
            P = scipy.linalg.solve_discrete_are(A.T, C.T, Qx, Rbar, s=S)
            innov = C @ P @ C.T + Rbar
            L = np.linalg.solve(innov, (A @ P @ C.T + S).T).T
        else:
            P = scipy.linalg.solve_continuous_are(A.T, C.T, Qx, Rbar, s=S)
            innov = Rbar
            L = np.linalg.solve(Rbar, (P @ C.T + S).T).T
    except (np.linalg.LinAlgError, ValueError) as exc:
        modes = unobservable_modes(A, C)
        raise DesignError(
            f"the Kalman Riccati equation has no stabilising solution ({exc}); "
            f"unobservable modes: {np.round(modes, 6).tolist()}; check R > 0 and detectability"
        ) from exc
    poles = scipy.linalg.eigvals(A - L @ C)
    _check_stable(model, poles, "the Kalman filter")
    return ObserverDesign(observer_generator(model, L, isolates=isolates, names=names), L, poles, (P + P.T) / 2,
                          (innov + innov.T) / 2, model=model)
