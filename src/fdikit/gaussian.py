"""Linear and nonlinear Gaussian state-space models (Hallouzi 2008, (2.1)–(2.4) and §2.3.3).

The model layer of the Kalman filter, the EKF, the IMM and the convex-model filters
(:mod:`fdikit.multimodel`):

* :class:`LinearGaussianModel` — ``x⁺ = A x + B u + w``, ``y = C x + D u + v``, ``w ~ N(0, Q)``, ``v ~ N(0, R)``;
* :class:`NonlinearGaussianModel` — ``x⁺ = f(x, u) + w``, ``y = h(x, u) + v`` with optional Jacobians.

Examples
--------
>>> LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]]).n
1
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import ModelError
from fdikit.model import FaultModel

__all__ = ["LinearGaussianModel", "NonlinearGaussianModel", "Fun"]

#: A model function ``(x, u) -> vector`` (state transition or measurement) or its Jacobian ``(x, u) -> matrix``.
Fun = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True, eq=False)
class LinearGaussianModel:
    """Discrete linear Gaussian model ``x⁺ = A x + B u + w``, ``y = C x + D u + v`` (Hallouzi 2008, (2.3)–(2.4)).

    ``Q = cov(w)`` (n x n) and ``R = cov(v)`` (p x p) are the state-space covariances
    (the thesis's ``(Q)^{1/2} w̄`` with unit-variance ``w̄``).  Build from a discrete
    :class:`~fdikit.model.FaultModel` with :meth:`from_fault_model` (uses ``A, Bu, C, Du``).
    ``name`` labels the model as one mode of a bank (the IMM's hypotheses).

    Parameters
    ----------
    A : array_like
        State matrix (n x n).
    C : array_like
        Output matrix (p x n).
    Q : array_like
        Process noise covariance ``cov(w)`` (n x n), symmetric positive semidefinite.
    R : array_like
        Measurement noise covariance ``cov(v)`` (p x p), positive definite.
    B : array_like, optional
        Input matrix (n x m); no inputs (m = 0) if omitted.
    D : array_like, optional
        Feedthrough matrix (p x m); zero if omitted.
    name : str, optional
        Label of the model (e.g. the mode name in an IMM bank); default ``""``.

    Attributes
    ----------
    A, B, C, D, Q, R : ndarray
        The matrices above, read-only.
    name : str
        The label.

    Raises
    ------
    ModelError
        If a matrix has the wrong shape, ``Q`` or ``R`` is not symmetric PSD, or ``R`` is singular.

    Examples
    --------
    >>> mdl = LinearGaussianModel(A=[[0.9]], C=[[1.0]], Q=[[0.1]], R=[[1.0]], name="nominal")
    >>> mdl.n, mdl.m, mdl.p, mdl.B.shape, mdl.name
    (1, 0, 1, (1, 0), 'nominal')
    >>> from fdikit.plants import white_speyer
    >>> plant = white_speyer().discretize(0.1)
    >>> LinearGaussianModel.from_fault_model(plant, Q=0.01 * np.eye(plant.n), R=np.eye(plant.p)).p
    2
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    name: str = ""

    def __init__(self, A, C, Q, R, B=None, D=None, name: str = "") -> None:
        A = validate.as_matrix("A", A, error=ModelError, promote=True)
        n = A.shape[0]
        if A.shape != (n, n):
            raise ModelError(f"A must be square, got shape {A.shape}")
        C = validate.as_matrix("C", C, (None, n), error=ModelError, promote=True)
        p = C.shape[0]
        B = np.zeros((n, 0)) if B is None else validate.as_matrix("B", B, (n, None), error=ModelError, promote=True)
        D = (np.zeros((p, B.shape[1])) if D is None
             else validate.as_matrix("D", D, (p, B.shape[1]), error=ModelError, promote=True))
        Q = validate.psd_part("Q", validate.as_matrix("Q", Q, (n, n), error=ModelError, promote=True), error=ModelError)
        R = validate.psd_part("R", validate.as_matrix("R", R, (p, p), error=ModelError, promote=True), error=ModelError)
        if p and np.linalg.eigvalsh(R)[0] <= 1e-14 * max(1.0, float(np.max(np.abs(R)))):
            raise ModelError("R must be positive definite (the innovation covariance must be invertible)")
        object.__setattr__(self, "name", str(name))
        for key, val in zip("ABCDQR", (A, B, C, D, Q, R), strict=True):
            val = np.array(val)
            val.setflags(write=False)
            object.__setattr__(self, key, val)

    @classmethod
    def from_fault_model(cls, model: FaultModel, Q, R) -> LinearGaussianModel:
        """Take ``A, Bu, C, Du`` of a discrete ``FaultModel``; ``Q``, ``R`` are state/output covariances."""
        if not isinstance(model, FaultModel):
            raise ModelError(f"expected a FaultModel, got {type(model).__name__}")
        if not model.is_discrete:
            raise ModelError("the Kalman filter needs a discrete model; discretize it first (model.discretize(dt))")
        return cls(model.A, model.C, Q, R, B=model.Bu, D=model.Du)

    @property
    def n(self) -> int:
        """Number of states."""
        return self.A.shape[0]

    @property
    def p(self) -> int:
        """Number of outputs."""
        return self.C.shape[0]

    @property
    def m(self) -> int:
        """Number of inputs."""
        return self.B.shape[1]


@dataclass(frozen=True, eq=False)
class NonlinearGaussianModel:
    """``x⁺ = f(x, u) + w``, ``y = h(x, u) + v`` with ``cov(w) = Q``, ``cov(v) = R``.

    ``f_jacobian(x, u)`` / ``h_jacobian(x, u)`` are optional analytic Jacobians; when
    omitted, central finite differences are used (:func:`numerical_jacobian`).
    ``n_inputs`` is the length of ``u`` (0: ``u`` is an empty vector).

    Parameters
    ----------
    f : callable
        State transition ``f(x, u) -> x_next`` (n).
    h : callable
        Measurement ``h(x, u) -> y`` (p).
    Q : array_like
        Process noise covariance (n x n); its size fixes ``n``.
    R : array_like
        Measurement noise covariance (p x p), positive definite; its size fixes ``p``.
    n_inputs : int, optional
        Length of ``u`` (default 0).
    f_jacobian, h_jacobian : callable, optional
        Analytic Jacobians ``(x, u) -> (n x n)`` and ``(x, u) -> (p x n)``; finite differences if None.

    Raises
    ------
    ModelError
        If ``Q``/``R`` are not symmetric PSD (``R`` positive definite), or ``f``, ``h`` or a Jacobian is
        not callable.

    Examples
    --------
    >>> mdl = NonlinearGaussianModel(f=lambda x, u: x + 0.1 * np.sin(x), h=lambda x, u: x, Q=[[0.01]], R=[[0.1]])
    >>> mdl.n, mdl.p, mdl.n_inputs
    (1, 1, 0)
    """

    f: Fun
    h: Fun
    Q: np.ndarray
    R: np.ndarray
    n_inputs: int = 0
    f_jacobian: Fun | None = None
    h_jacobian: Fun | None = None

    def __post_init__(self) -> None:
        Q = validate.as_matrix("Q", self.Q, error=ModelError, promote=True)
        R = validate.as_matrix("R", self.R, error=ModelError, promote=True)
        object.__setattr__(self, "Q", validate.psd_part("Q", Q, error=ModelError))
        object.__setattr__(self, "R", validate.psd_part("R", R, error=ModelError))
        if not callable(self.f) or not callable(self.h):
            raise ModelError("f and h must be callables f(x, u) -> x_next, h(x, u) -> y")
        object.__setattr__(self, "n_inputs", validate.integer("n_inputs", self.n_inputs, minimum=0, error=ModelError))
        for nm in ("f_jacobian", "h_jacobian"):
            if getattr(self, nm) is not None and not callable(getattr(self, nm)):
                raise ModelError(
                    f"{nm} must be a callable (x, u) -> matrix or None, got {type(getattr(self, nm)).__name__}"
                )
        if np.linalg.eigvalsh(self.R)[0] <= 0:
            raise ModelError("R must be positive definite (the innovation covariance must be invertible)")

    @property
    def n(self) -> int:
        """Number of states."""
        return self.Q.shape[0]

    @property
    def p(self) -> int:
        """Number of outputs."""
        return self.R.shape[0]
