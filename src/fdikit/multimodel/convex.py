"""Convex-model (CM) structure (Hallouzi 2008, §2.2.2) and its limit-value form (§3.5).

The CM structure (2.8)–(2.10) blends ``N`` local models with weights on the simplex,

    x_{k+1} = Σ μ^(i) (A^(i) x_k + B^(i) u_k) + Q^{1/2} w_k,
    y_k     = Σ μ^(i) (C^(i) x_k + D^(i) u_k) + R^{1/2} v_k,      μ ≥ 0, 1ᵀμ = 1,

with noise common to all models (:class:`ConvexModelSet`, built by :func:`convex_model_set`;
:func:`limit_value_convex_set` gives the limit-value model (3.39)–(3.40) in the same form).

The filters on this structure are the dual CMF (Table 2.2) in :mod:`fdikit.multimodel.convex_filter` and the
augmented EKF (Table 2.3) in :mod:`fdikit.multimodel.convex_ekf`; fault sizes and parameters are reconstructed
from the weights in :mod:`fdikit.multimodel.reconstruction`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, ModelError
from fdikit.multimodel.kalman_steps import psd_sqrt

__all__ = [
    "ConvexModelSet",
    "convex_model_set",
    "limit_value_convex_set",
]


@dataclass(frozen=True)
class ConvexModelSet:
    """``N`` local discrete models ``(A, B, C, D)^(i)`` with common noise ``Q``, ``R`` (Hallouzi 2008, (2.8)–(2.10)).

    Attributes
    ----------
    A, B, C, D : ndarray
        Local matrices, stacked: A (N, n, n), B (N, n, m), C (N, p, n), D (N, p, m).
    Q, R : ndarray
        Process-noise covariance (n, n) and measurement-noise covariance (p, p).
    names : tuple of str
        Model names.
    varying : tuple of bool
        Which of (A, B, C, D) differ between models.  A matrix common to all models is treated as
        a constant, not as ``Σ μ^(i) M = (1ᵀμ) M``: both agree on the simplex, but only the former has a zero
        derivative in μ, so that the augmented EKF is the linear KF on ``[x; μ]`` when only B varies, as
        §2.4.2 states.
    offset : tuple of ndarray or None
        ``(A⁺, B⁺, C⁺, D⁺)`` added to every blend, for the limit-value structure (3.39)–(3.40)
        ``M(μ) = M⁺ + Σ μ_j M^Δ_j`` (the local "models" are then the changes ``M^Δ_j``; see
        :func:`limit_value_convex_set`).  ``None`` for a convex model.

    Examples
    --------
    Build it with :func:`convex_model_set`:

    >>> ms = convex_model_set([[0.9]], [[[0.0]], [[1.0]]], [[1.0]], Q=[[1e-4]], R=[[1e-2]],
    ...                       names=["stuck", "nominal"])
    >>> ms.N, ms.varying
    (2, (False, True, False, False))
    >>> [M.tolist() for M in ms.blend([0.25, 0.75])]
    [[[0.9]], [[0.75]], [[1.0]], [[0.0]]]

    References
    ----------
    Hallouzi 2008, §2.2.2, (2.8)–(2.10); §2.3.2, (2.19)–(2.20) for the blend.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    names: tuple[str, ...]
    varying: tuple[bool, bool, bool, bool] = (True, True, True, True)
    offset: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    @property
    def N(self) -> int:
        return self.A.shape[0]

    @property
    def n(self) -> int:
        return self.A.shape[1]

    @property
    def m(self) -> int:
        return self.B.shape[2]

    @property
    def p(self) -> int:
        return self.C.shape[1]

    def check_weights(self, mu) -> np.ndarray:
        mu = validate.as_array("weights", mu, error=DataError, finite=False).ravel()
        if mu.size != self.N or not np.all(np.isfinite(mu)):
            raise DataError(f"weights must be {self.N} finite numbers (one per model), got {mu.size}")
        return mu

    def blend(self, mu) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A_μ, B_μ, C_μ, D_μ) = Σ μ^(i) (A, B, C, D)^(i)`` (Hallouzi 2008, (2.19)–(2.20))."""
        mu = self.check_weights(mu)
        mats = (self.A, self.B, self.C, self.D)
        out = tuple(np.tensordot(mu, M, axes=1) if v else M[0].copy() for M, v in zip(mats, self.varying))
        return out if self.offset is None else tuple(o + M for o, M in zip(self.offset, out))

    def weight_columns(self, x, u) -> tuple[np.ndarray, np.ndarray]:
        """``∂(A_μ x + B_μ u)/∂μ`` (n, N) and ``∂(C_μ x + D_μ u)/∂μ`` (p, N); constant matrices add nothing."""
        va, vb, vc, vd = self.varying
        fx = (self.A @ x if va else 0.0) + (self.B @ u if vb else 0.0)
        hx = (self.C @ x if vc else 0.0) + (self.D @ u if vd else 0.0)
        return (np.broadcast_to(fx, (self.N, self.n)).T.copy(), np.broadcast_to(hx, (self.N, self.p)).T.copy())


def convex_model_set(A, B, C, D=None, Q=None, R=None, names=None) -> ConvexModelSet:
    """Build a :class:`ConvexModelSet` (Hallouzi 2008, §2.2.2).

    Each of ``A, B, C, D`` is either one matrix shared by all models or a sequence/stack of ``N``
    matrices; ``N`` is taken from the stacked ones.  ``D`` defaults to zero.

    Parameters
    ----------
    A, B, C : array_like
        State (n x n), input (n x m) and output (p x n) matrices, each one matrix or a stack of N;
        at least one is a stack.
    D : array_like, optional
        Feedthrough (p x m) or a stack of N; zero if omitted.
    Q, R : array_like
        Common process (n x n, PSD) and measurement (p x p, positive definite) noise covariances; required.
    names : sequence of str, optional
        N model names; default ``"model_1"``, ``"model_2"``, ….

    Returns
    -------
    ConvexModelSet
        The set, with ``varying`` marking the matrices that differ between the models.

    Raises
    ------
    ModelError
        If no matrix is stacked, the stacks disagree on N, the shapes do not fit, ``Q``/``R`` are missing or
        not covariances, or the number of names is not N.

    Examples
    --------
    >>> ms = convex_model_set(np.eye(1), [[[0.0]], [[2.0]]], np.eye(1), Q=np.eye(1), R=np.eye(1))
    >>> ms.N, ms.blend([0.25, 0.75])[1]
    (2, array([[1.5]]))

    References
    ----------
    Hallouzi 2008, §2.2.2, (2.8)–(2.10).
    """
    mats = {"A": A, "B": B, "C": C}
    arrs = {k: np.asarray(v, dtype=float) for k, v in mats.items()}
    Ns = {a.shape[0] for a in arrs.values() if a.ndim == 3}
    if len(Ns) > 1:
        raise ModelError(f"stacked A, B, C disagree on the number of models {sorted(Ns)}; give N of each")
    if not Ns:
        raise ModelError("no model varies: pass at least one of A, B, C as a stack of N >= 2 matrices")
    N = Ns.pop()
    stacked = {k: (a if a.ndim == 3 else np.broadcast_to(a, (N, *a.shape)).copy()) for k, a in arrs.items()}
    for k, a in stacked.items():
        if a.ndim != 3 or not np.all(np.isfinite(a)):
            raise ModelError(f"{k} must be finite 2-D matrices (or a stack of them), got shape {a.shape}")
    A_, B_, C_ = stacked["A"], stacked["B"], stacked["C"]
    n, m, p = A_.shape[1], B_.shape[2], C_.shape[1]
    if A_.shape[1:] != (n, n) or B_.shape[1] != n or C_.shape[2] != n:
        raise ModelError(f"shapes do not fit: A {A_.shape[1:]}, B {B_.shape[1:]}, C {C_.shape[1:]}; "
                         "need n x n, n x m, p x n")
    D_ = np.zeros((N, p, m)) if D is None else np.asarray(D, dtype=float)
    if D_.ndim == 2:
        D_ = np.broadcast_to(D_, (N, *D_.shape)).copy()
    if D_.shape != (N, p, m):
        raise ModelError(f"D must be {p} x {m} (or a stack of {N}), got {D_.shape}")
    if Q is None or R is None:
        raise ModelError("give the noise covariances Q (n x n) and R (p x p) of the convex model (2.8)-(2.9)")
    Q_, R_ = np.asarray(Q, dtype=float), np.asarray(R, dtype=float)
    if Q_.shape != (n, n) or R_.shape != (p, p):
        raise ModelError(f"Q must be {n} x {n} and R {p} x {p}, got {Q_.shape} and {R_.shape}")
    psd_sqrt(Q_, "Q")
    if not (np.all(np.isfinite(R_)) and np.allclose(R_, R_.T) and np.linalg.eigvalsh(R_).min() > 0):
        raise ModelError("R must be symmetric positive definite (the filters invert it)")
    names = tuple(names) if names is not None else tuple(f"model_{i + 1}" for i in range(N))
    if len(names) != N:
        raise ModelError(f"{len(names)} names for {N} models")
    varying = tuple(bool(np.ptp(M, axis=0).max() > 0) if M.size else False for M in (A_, B_, C_, D_))
    return ConvexModelSet(A_, B_, C_, D_, Q_, R_, names, varying)


def limit_value_convex_set(lv, Q, R) -> ConvexModelSet:
    """The limit-value model (Hallouzi 2008, (3.39)–(3.40), (3.44)) as a :class:`ConvexModelSet` with an offset.

    ``lv`` is a :class:`~fdikit.multimodel.lv_design.LimitValueModelSet`.  Each weight ``μ_j ∈ [0, 1]`` scales
    its change ``M^Δ_j``; there is no sum constraint (filter with ``constrain="box"``), and the Jacobian
    columns of the augmented EKF are ``A^Δ_j x + B^Δ_j u`` and ``C^Δ_j x + D^Δ_j u`` (the derivatives of the
    blended model with respect to ``μ_j``).

    Parameters
    ----------
    lv : LimitValueModelSet
        The limit-value set (offset ``M⁺`` and changes ``M^Δ_j``), from
        :func:`~fdikit.multimodel.lv_design.limit_value_model_set`.
    Q, R : array_like
        Process (n x n) and measurement (p x p) noise covariances.

    Returns
    -------
    ConvexModelSet
        One "model" per limit-value weight (the changes ``M^Δ_j``), with ``offset = (A⁺, B⁺, C⁺, D⁺)``.

    Raises
    ------
    ModelError
        If ``lv`` has no varying parameter (or as :func:`convex_model_set`).

    Examples
    --------
    >>> from fdikit.multimodel.lv_design import limit_value_model_set
    >>> lv = limit_value_model_set(lambda a: ([[a]], [[1.0]], [[1.0]]), {"a": -1.0}, {"a": -3.0})
    >>> ms = limit_value_convex_set(lv, Q=[[1.0]], R=[[1.0]])
    >>> float(ms.blend([0.5])[0][0, 0]), ms.names
    (-2.0, ('a',))

    References
    ----------
    Hallouzi 2008, §3.5, (3.34)–(3.40); §3.6.1, (3.44).
    """
    deltas = lv.deltas
    if not deltas:
        raise ModelError("the limit-value model set has no varying parameter")
    stacks = [np.stack([d[i] for d in deltas]) for i in range(4)]
    ms = convex_model_set(stacks[0], stacks[1], stacks[2], stacks[3], Q=Q, R=R, names=lv.names)
    # a matrix that no parameter changes has all-zero deltas: its blend is the offset alone
    varying = tuple(bool(np.abs(M).max() > 0) if M.size else False for M in stacks)
    return ConvexModelSet(*stacks, ms.Q, ms.R, ms.names, varying,
                          tuple(np.asarray(o, dtype=float) for o in lv.offset))
