"""The γ → 0 limit of the game filter: Goh transformation (Algorithm 4.1) and the Goh Riccati equation.

As γ → 0 with the sensor-noise weight scaled along (``V = V̄/γ`` fixed, Murray 2012, §4.1; PATH's
``V̄ = lim ν/γ``), the game filter's cost becomes *singular* in the nuisance fault (Douglas et al.
1996, (9.35): ``Π F̂ = 0``).  Goh transformations ``ρ = ∫ μ̂``, ``α = x − B ρ`` move the nuisance to
an input that reaches the output, and the limiting Riccati equation — the **Goh Riccati
equation** — is regular again (Douglas et al. 1996, (9.36)–(9.44); Murray 2012, §4.1.1, (4.33)).

* :func:`goh_transformation` — Murray 2012, **Algorithm 4.1** (LTI: time derivatives zero).  It
  returns ``B̃`` (the transformed nuisance directions, ``C B̃`` of full column rank), ``B̂ = A B̃``
  (their Goh-transformed input map) and ``B̄`` (all directions met), with ``Ŵ* = Im B̄`` (4.18), the
  minimal (C, A)-invariant subspace containing ``Im F̂``, and ``C Ŵ* = Im C B̃`` (4.19).
* :func:`goh_riccati` — the steady state of the Goh Riccati equation (9.44)/(4.33) started at
  ``S(t0) = 0`` (9.41)::

      0 = S Ã + Ãᵀ S + S B̂ Ξ B̂ᵀ S + Cᵀ (Ĥ Q Ĥ − H̄ᵀ V⁻¹ H̄) C,
      Ã = A − B̂ Ξ B̃ᵀ Cᵀ V⁻¹ C,   Ξ = (B̃ᵀ Cᵀ V⁻¹ C B̃)⁻¹,   H̄ = I − C B̃ Ξ B̃ᵀ Cᵀ V⁻¹  (4.31).

  Expanding PATH's (9.44) ``[S(A B_i) − Cᵀ V̄⁻¹ C B_i] (B_iᵀ Cᵀ V̄⁻¹ C B_i)⁻¹ [·]ᵀ`` gives exactly this
  with ``B_i = B̃``; Algorithm 4.1 also covers nuisance columns of different relative degree,
  where PATH's single ``B_i`` does not.  ``S`` has ``Ŵ*`` in its kernel (``S B̄ = 0``, Murray
  Theorem 4.2; ``S F̂ = 0``, PATH Prop. 9.2/(9.48)), plus the directions of the invariant zeros of
  ``(C, A, F̂)`` in the closed right half-plane (PATH Theorem 9.4).  It is computed in the
  coordinates that split off that kernel: with an orthonormal ``Γ = [Γ₁; Γ₂]`` (``Im Γ₂ᵀ = Ker S``),
  ``Γ S Γᵀ = blkdiag(S̄, 0)`` (9.57) and ``S̄ > 0`` solves the reduced Goh Riccati equation (9.77)
  (the (1,1) block of the equation above; the other blocks vanish identically)::

      0 = S̄ Ā + Āᵀ S̄ + S̄ G Gᵀ S̄ − C₁ᵀ Ψ C₁,   Ā = Γ₁ Ã Γ₁ᵀ,  G Gᵀ = Γ₁ B̂ Ξ B̂ᵀ Γ₁ᵀ,
      Ψ = H̄ᵀ V⁻¹ H̄ − Ĥ Q Ĥ,   C₁ = C Γ₁ᵀ.

  The solution reached from ``S̄(t0) = 0`` is the one with ``−Ā − G Gᵀ S̄`` Hurwitz (the stabilizing
  solution of the equation for ``−Ā``, computed by :func:`scipy.linalg.solve_continuous_are`);
  :func:`goh_riccati_transient` integrates (9.77) forward to confirm it.

Integrating the full n x n equation (9.44) directly is numerically unstable: its kernel block obeys
``Ṡ₂₂ = −S₂₁ G Gᵀ S₁₂ − …`` with ``‖B̂ Ξ B̂ᵀ‖`` ≈ 9e5 in the PATH example, so round-off in ``S B̃`` is
driven negative and blows up in finite time (the ill-conditioning warned of at the end of PATH
§9.5).  The reduced coordinates keep ``S B̄ = 0`` exactly.

Weights: ``V`` is Murray's ``V = V̄/γ`` held fixed as γ → 0, which is PATH's ``V̄`` of (9.35)
(PATH defines ``V̄ = lim γV`` but uses ``V̄⁻¹ = lim γ V⁻¹``; with ``V_PATH = ν I`` it is ``ν/γ``, 0.8 in
§9.6 — the same number as the ``V`` argument of :func:`fdikit.design.game.single_fault.single_fault_game_filter`).
``Q`` weights ``Ĥ C e``.  ``Ψ ≥ 0`` (e.g. scalar ``Q ≤ 1/V``) guarantees a solution; otherwise it is
an indefinite (H∞-type) equation that may have none.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.integrate import solve_ivp

from fdikit import linalg, validate
from fdikit.design.game.setup import weight
from fdikit.errors import DesignError, ModelError, ParameterError

__all__ = [
    "GohTransformation",
    "GohRiccatiSolution",
    "goh_transformation",
    "goh_riccati",
    "goh_riccati_rhs",
    "goh_riccati_transient",
    "oblique_projector",
]

_EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class GohTransformation:
    """Result of Murray 2012, Algorithm 4.1 (LTI).

    Attributes
    ----------
    B_hat : ``B̂ = A B̃`` (n x k), the input map of the transformed nuisance (Step 7).
    B_tilde : ``B̃`` (n x k), transformed nuisance directions; ``C B̃`` has full column rank.
    B_bar : ``B̄`` (n x m), every direction met; ``Im B̄ = Ŵ*`` (4.18).
    iterations : ``β̂``, the number of Goh transformations (0 when ``C F̂`` has full column rank).

    The property ``invariant_subspace`` is an orthonormal basis of ``Ŵ* = Im B̄``.

    Examples
    --------
    >>> g = goh_transformation([[0, 1], [0, 0]], [[1, 0]], [[0], [1]])
    >>> g.iterations, g.invariant_subspace.shape
    (1, (2, 2))

    References
    ----------
    Murray 2012, §4.1.2, Algorithm 4.1.
    """

    B_hat: np.ndarray
    B_tilde: np.ndarray
    B_bar: np.ndarray
    iterations: int

    @property
    def invariant_subspace(self) -> np.ndarray:
        """Orthonormal basis of ``Ŵ* = Im B̄``."""
        return linalg.orth(self.B_bar) if self.B_bar.shape[1] else self.B_bar


def _rank_tol(C: np.ndarray, B: np.ndarray, rtol: float | None) -> float:
    """Absolute threshold for ``C B`` singular values, relative to ‖C‖‖B‖ (not to ‖C B‖)."""
    r = rtol if rtol is not None else 1e3 * max(C.shape + B.shape) * _EPS
    return r * max(np.linalg.norm(C, 2) * np.linalg.norm(B, 2), _EPS)


def goh_transformation(A, C, F, rtol: float | None = None) -> GohTransformation:
    """Goh transformation of a nuisance direction: Murray 2012, Algorithm 4.1, Steps 1–8 (LTI).

    Step 1 ``B̂⁰ = B̃⁰ = B̄⁰ = F``; then, while ``Im B̃ᵏ ∩ Ker C ≠ 0`` (Step 3), split
    ``B̃ᵏ T = [B̃₁, B̃₂]`` with ``Im B̃₂ = Im B̃ᵏ ∩ Ker C`` (Step 4), replace ``B̃₂`` by ``A B̃₂`` in ``B̃``
    and append it to ``B̄`` (Steps 5–6), ``B̂ = A B̃`` (Step 7).  Time derivatives vanish for an LTI
    model.  Implemented from the Steps, not from the garbled closed forms (4.10)–(4.14).  The
    columns of ``B̃`` are re-orthonormalised each pass (the Goh Riccati equation depends on
    ``Im B̃`` only), which keeps powers of ``A`` from blowing up.

    Parameters
    ----------
    A, C : state and output matrices.
    F : n x k nuisance direction ``F̂`` (k may be 0).
    rtol : rank tolerance relative to ``‖C‖ ‖B̃‖``.

    Returns
    -------
    GohTransformation
        ``B̂``, ``B̃``, ``B̄`` and the number of steps.

    Raises
    ------
    ModelError
        ``A``, ``C``, ``F`` of inconsistent sizes or with non-finite entries.
    DesignError
        If ``F`` is rank deficient (not monic) or a direction never reaches the output (it lies in
        the unobservable subspace of (C, A)), so the iteration does not stop within n steps.

    Examples
    --------
    A double integrator with a force disturbance (relative degree 2): one Goh step.

    >>> g = goh_transformation([[0, 1], [0, 0]], [[1, 0]], [[0], [1]])
    >>> g.iterations, g.B_bar.shape, g.B_tilde.ravel().tolist()
    (1, (2, 2), [1.0, 0.0])

    References
    ----------
    Murray 2012, §4.1.2, Algorithm 4.1, Steps 1–8.
    """
    A = validate.as_square("A", A, error=ModelError)
    n = A.shape[0]
    C = validate.as_matrix("C", C, error=ModelError, promote=True)
    if C.shape[1] != n:
        raise ModelError(f"C has {C.shape[1]} columns but A is {n} x {n}")
    F = np.asarray(F, dtype=float).reshape(n, -1)
    if F.shape[1] == 0:
        empty = np.zeros((n, 0))
        return GohTransformation(empty, empty, empty, 0)
    if linalg.rank(F, rtol) < F.shape[1]:
        raise DesignError(
            f"the nuisance direction F̂ (n x {F.shape[1]}) has rank {linalg.rank(F, rtol)}: it is not monic; "
            "drop the dependent columns"
        )
    Bt = linalg.orth(F, rtol)
    Bbar = F.copy()
    for k in range(n + 1):
        M = C @ Bt
        _, s, Vh = np.linalg.svd(M)
        s = np.concatenate([s, np.zeros(Bt.shape[1] - s.size)])
        visible = s > _rank_tol(C, Bt, rtol)
        if visible.all():  # Step 3: Im B̃ ∩ Ker C = 0
            return GohTransformation(A @ Bt, Bt, Bbar, k)
        T1, T2 = Vh[visible].T, Vh[~visible].T  # Step 4: B̃ T = [B̃₁, B̃₂], B̃₂ spans Im B̃ ∩ Ker C
        B2 = A @ (Bt @ T2)  # Step 5: B̂₂ = A B̃₂
        new = np.hstack([Bt @ T1, B2])  # Step 6
        if linalg.rank(new, rtol) < new.shape[1]:
            raise DesignError(
                "Algorithm 4.1 lost rank: a nuisance direction in Ker C is mapped by A into the span of the others "
                "without reaching the output (an unobservable direction of (C, A)); the nuisance cannot be blocked "
                "by a limiting game filter"
            )
        Bbar = np.hstack([Bbar, B2])
        Bt = linalg.orth(new, rtol)
    raise DesignError(
        f"Algorithm 4.1 did not stop within n = {n} Goh transformations: part of Im F̂ never reaches the output "
        "(it lies in the unobservable subspace of (C, A)); make (C, A) observable or drop that nuisance"
    )


def oblique_projector(C: np.ndarray, B_tilde: np.ndarray, V: np.ndarray) -> np.ndarray:
    """``H̄ = I − C B̃ (B̃ᵀ Cᵀ V⁻¹ C B̃)⁻¹ B̃ᵀ Cᵀ V⁻¹`` (Murray 2012, (4.31)); ``Ker H̄ = Im C B̃``.

    For ``V = v I`` it is the orthogonal projector ``Ĥ``; with ``C F̂`` of full rank it is PATH's
    ``I − C₂ K`` of (9.62)–(9.63).

    Parameters
    ----------
    C : (p, n) array
        Output matrix.
    B_tilde : (n, k) array
        ``B̃`` of :func:`goh_transformation` (``C B̃`` of full column rank; k = 0 gives ``I``).
    V : (p, p) array
        Positive definite noise weight ``V = V̄/γ``.

    Returns
    -------
    numpy.ndarray
        ``H̄`` (p x p), idempotent, kernel ``Im C B̃``.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(oblique_projector(np.eye(2), np.array([[1.0], [1.0]]), np.diag([1.0, 2.0])), 6)
    array([[ 0.333333, -0.333333],
           [-0.666667,  0.666667]])

    References
    ----------
    Murray 2012, §4.2.1, (4.31); Douglas et al. 1996, §9.5, (9.62)–(9.63).
    """
    C, V = np.asarray(C, dtype=float), np.asarray(V, dtype=float)
    p = C.shape[0]
    if B_tilde.shape[1] == 0:
        return np.eye(p)
    Vi = np.linalg.inv(V)
    CB = C @ B_tilde
    return np.eye(p) - CB @ np.linalg.solve(CB.T @ Vi @ CB, CB.T @ Vi)


def goh_riccati_rhs(S, A, C, goh: GohTransformation, V, Q, H) -> np.ndarray:
    """Right-hand side of ``−Ṡ = …`` of the Goh Riccati equation (Murray (4.33) ≡ PATH (9.44)).

    ``S Ã + Ãᵀ S + S B̂ Ξ B̂ᵀ S + Cᵀ (Ĥ Q Ĥ − H̄ᵀ V⁻¹ H̄) C`` (module docstring); zero at a steady state.

    Parameters
    ----------
    S : (n, n) array
        The point at which the right-hand side is evaluated.
    A, C : (n, n) and (p, n) arrays
        Plant matrices (continuous time).
    goh : GohTransformation
        Algorithm 4.1 applied to ``F̂`` (:func:`goh_transformation`).
    V, Q, H : (p, p) arrays
        Noise weight ``V = V̄/γ``, output weight and the orthogonal projector ``Ĥ``.

    Returns
    -------
    numpy.ndarray
        The (n, n) right-hand side.

    Examples
    --------
    The steady state of :func:`goh_riccati` makes it vanish:

    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer("unstable-zero")
    >>> sol = goh_riccati(m.A, m.C, m.Bf[:, [1]], V=1.0, Q=0.002)
    >>> bool(np.abs(goh_riccati_rhs(sol.S, m.A, m.C, sol.goh, sol.V, sol.Q, sol.projector)).max() < 1e-8)
    True

    References
    ----------
    Murray 2012, §4.2.1, (4.33); Douglas et al. 1996, §9.3.2, (9.44).
    """
    A, C, S = (np.asarray(M, dtype=float) for M in (A, C, S))
    V, Q, H = (np.asarray(M, dtype=float) for M in (V, Q, H))
    Vi = np.linalg.inv(V)
    Bt, Bh = goh.B_tilde, goh.B_hat
    CB = C @ Bt
    Xi = np.linalg.inv(CB.T @ Vi @ CB) if Bt.shape[1] else np.zeros((0, 0))
    At = A - Bh @ Xi @ CB.T @ Vi @ C
    Hb = oblique_projector(C, Bt, V)
    return S @ At + At.T @ S + S @ Bh @ Xi @ Bh.T @ S + C.T @ (H @ Q @ H - Hb.T @ Vi @ Hb) @ C


@dataclass(frozen=True, eq=False)
class GohRiccatiSolution:
    """Steady-state solution of the Goh Riccati equation and its kernel split.

    Attributes
    ----------
    S : n x n, ``S ≥ 0``, ``S B̄ = 0`` (PATH (9.44), (9.48); Murray (4.33), Theorem 4.2).
    S_reduced : ``S̄ > 0`` (n₁ x n₁), the solution of the reduced equation (9.77).
    transformation : orthonormal ``Γ`` (n x n, rows ``[Γ₁; Γ₂]``) with ``Γ S Γᵀ = blkdiag(S̄, 0)`` (9.57).
    order : ``n₁ = n − dim Ker S``.
    goh : the :class:`GohTransformation` of ``F̂``.
    projector : ``Ĥ`` (orthogonal, kernel ``C Ŵ*``).
    oblique_projector : ``H̄`` (4.31).
    V, Q : the weights (p x p).
    kernel_zeros : invariant zeros of ``(C, A, F̂)`` with ``Re ≥ 0`` whose directions are in ``Ker S``
        (PATH Theorem 9.4).
    residual : ``‖goh_riccati_rhs(S)‖ / (‖Cᵀ(ĤQĤ − H̄ᵀV⁻¹H̄)C‖ + 2‖Ã‖‖S‖ + ‖B̂ΞB̂ᵀ‖‖S‖²)``.

    The property ``kernel`` is an orthonormal basis of ``Ker S`` (``Γ₂ᵀ``).

    Examples
    --------
    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer("unstable-zero")
    >>> sol = goh_riccati(m.A, m.C, m.Bf[:, [1]], V=1.0, Q=0.002)
    >>> sol.S_reduced.shape, sol.kernel.shape
    ((1, 1), (3, 2))

    References
    ----------
    Douglas et al. 1996, §9.3.2, (9.44), (9.48), §9.5, (9.57), (9.77); Murray 2012, §4.2.1, (4.33), Theorem 4.2.
    """

    S: np.ndarray
    S_reduced: np.ndarray
    transformation: np.ndarray
    order: int
    goh: GohTransformation
    projector: np.ndarray
    oblique_projector: np.ndarray
    V: np.ndarray
    Q: np.ndarray
    kernel_zeros: np.ndarray
    residual: float

    @property
    def kernel(self) -> np.ndarray:
        """Orthonormal basis of ``Ker S`` (n x (n − n₁)), ``= Γ₂ᵀ``."""
        return self.transformation[self.order :].T


def _orthogonal_projector(C: np.ndarray, W: np.ndarray) -> np.ndarray:
    p = C.shape[0]
    if W.shape[1] == 0:
        return np.eye(p)
    U = linalg.orth(C @ W)
    return np.eye(p) - U @ U.T


def _unstable_zero_directions(A, C, F, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Invariant zeros of (C, A, F) with Re z ≥ −1e-9·scale and the real span of their directions."""
    n = A.shape[0]
    if F.shape[1] == 0:
        return np.zeros(0, dtype=complex), np.zeros((n, 0))
    zeros, dirs = linalg.invariant_zeros(A, C, F)
    keep = [i for i, z in enumerate(zeros) if z.real >= -1e-9 * scale]
    if not keep:
        return np.zeros(0, dtype=complex), np.zeros((n, 0))
    V = np.column_stack([dirs[i] for i in keep])
    return zeros[keep], np.hstack([V.real, V.imag])


def _split(kernel: np.ndarray, n: int) -> tuple[np.ndarray, int]:
    """Orthonormal Γ (rows [Γ₁; Γ₂]) with Γ₂ᵀ spanning ``kernel``, and n₁ = n − dim kernel."""
    K = linalg.orth(kernel) if kernel.shape[1] else np.zeros((n, 0))
    comp = linalg.null(K.T) if K.shape[1] else np.eye(n)
    return np.vstack([comp.T, K.T]), comp.shape[1]


def _weights(C: np.ndarray, V, Q) -> tuple[np.ndarray, np.ndarray]:
    p = C.shape[0]
    Vw = weight("V", V, p)
    if np.linalg.eigvalsh(Vw).min() <= 1e-14 * max(1.0, np.abs(Vw).max()):
        raise ParameterError("weight V must be positive definite (it is inverted); e.g. V = 1.0")
    return Vw, weight("Q", Q, p)


def _prepare(A, C, F_hat, V, Q, projector, rtol):
    """Common data of the Goh Riccati equation: checked matrices, weights, Goh transformation, Ĥ and H̄."""
    A = validate.as_square("A", A, error=ModelError)
    n = A.shape[0]
    C = validate.as_matrix("C", C, (None, n), error=ModelError, promote=True)
    F = np.asarray(F_hat, dtype=float).reshape(n, -1)
    Vw, Qw = _weights(C, V, Q)
    goh = goh_transformation(A, C, F, rtol)
    H = _orthogonal_projector(C, goh.invariant_subspace) if projector is None else validate.as_matrix(
        "projector", projector, (C.shape[0], C.shape[0]))
    return A, C, F, Vw, Qw, np.linalg.inv(Vw), goh, H, oblique_projector(C, goh.B_tilde, Vw)


def goh_riccati(A, C, F_hat, *, V=1.0, Q=1e-4, projector=None, rtol: float | None = None) -> GohRiccatiSolution:
    """Steady state of the Goh Riccati equation from ``S(t0) = 0`` (Douglas et al. 1996, (9.44), (9.77)).

    Parameters
    ----------
    A, C : plant matrices (continuous time).
    F_hat : ``F̂`` (n x k), the complementary fault direction (nuisance and other targets).
    V : ``V = V̄/γ`` (PATH's ``V̄``), p x p positive definite or a scalar.
    Q : weight on ``Ĥ C e`` (p x p or scalar).
    projector : ``Ĥ`` (p x p); default the orthogonal projector annihilating ``C Ŵ*`` (3.10).
    rtol : rank tolerance of the subspace computations.

    Returns
    -------
    GohRiccatiSolution

    Raises
    ------
    DesignError
        If Algorithm 4.1 fails (see :func:`goh_transformation`), the reduced equation has no
        stabilizing solution, or ``S̄`` is not positive definite (``Q`` too large for ``V``, or a mode
        of the reduced system that the nuisance does not excite, for which ``S`` grows without bound).

    Examples
    --------
    White–Speyer (Murray 2012, §6.2.2): the unstable zero +3 of ``(C, A, F₂)`` joins ``Ker S``.

    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer("unstable-zero")
    >>> sol = goh_riccati(m.A, m.C, m.Bf[:, [1]], V=1.0, Q=0.002)
    >>> sol.order, np.round(sol.kernel_zeros.real, 6).tolist()
    (1, [3.0])

    References
    ----------
    Douglas et al. 1996, §9.3.2, (9.44), §9.4, Theorem 9.4, §9.5, (9.77); Murray 2012, §4.2, (4.33), §6.2.2.
    """
    A, C, F, Vw, Qw, Vi, goh, H, Hb = _prepare(A, C, F_hat, V, Q, projector, rtol)
    n, W = A.shape[0], goh.invariant_subspace
    scale = max(np.linalg.norm(A, 2), 1.0)
    zeros, Z = _unstable_zero_directions(A, C, F, scale)
    Gam, n1 = _split(np.hstack([W, Z]), n)
    if n1 == 0:
        raise DesignError("Ker S is the whole state space: the nuisance reaches every state, nothing is left to detect")
    G1 = Gam[:n1]
    CB = C @ goh.B_tilde
    Xi = np.linalg.inv(CB.T @ Vi @ CB) if goh.B_tilde.shape[1] else np.zeros((0, 0))
    At = A - goh.B_hat @ Xi @ CB.T @ Vi @ C
    Psi = Hb.T @ Vi @ Hb - H @ Qw @ H
    Abar = G1 @ At @ G1.T
    C1 = C @ G1.T
    q = C1.T @ Psi @ C1
    q = (q + q.T) / 2
    if goh.B_tilde.shape[1]:
        G = G1 @ goh.B_hat @ np.linalg.cholesky(Xi)
    else:
        G = np.zeros((n1, 1))
    try:
        Sbar = scipy.linalg.solve_continuous_are(-Abar, G, q, np.eye(G.shape[1]))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise DesignError(
            f"the reduced Goh Riccati equation (9.77) has no stabilizing solution ({exc}); a mode of the reduced "
            "system on the imaginary axis, or a Q too large for V (need V⁻¹ − Q ≥ 0 on the residual space)"
        ) from exc
    Sbar = (Sbar + Sbar.T) / 2
    ev = np.linalg.eigvalsh(Sbar)
    if ev.min() <= 1e-10 * max(ev.max(), _EPS):
        raise DesignError(
            f"the reduced Goh Riccati solution S̄ is not positive definite (eigenvalues {np.round(ev, 12).tolist()}): "
            "either Q is too large for V (use Q < 1/V) or a mode of the reduced system is not excited by the "
            "nuisance faults, so S grows without bound and the limiting filter does not exist"
        )
    S = G1.T @ Sbar @ G1
    S = (S + S.T) / 2
    rhs = goh_riccati_rhs(S, A, C, goh, Vw, Qw, H)
    den = (np.linalg.norm(C.T @ (H @ Qw @ H - Hb.T @ Vi @ Hb) @ C) + 2 * np.linalg.norm(At) * np.linalg.norm(S)
           + np.linalg.norm(goh.B_hat @ Xi @ goh.B_hat.T) * np.linalg.norm(S) ** 2)
    return GohRiccatiSolution(S, Sbar, Gam, n1, goh, H, Hb, Vw, Qw, zeros, float(np.linalg.norm(rhs) / max(den, _EPS)))


def goh_riccati_transient(A, C, F_hat, t: Sequence[float], *, V=1.0, Q=1e-4, S0=None, projector=None,
                          rtol: float | None = None, tol: float = 1e-10) -> np.ndarray:
    """``S(t)`` of the Goh Riccati equation forward from ``S(0)`` (Douglas et al. 1996, (9.77)–(9.78)).

    Integrates the reduced equation ``−dS̄/dt = S̄ Ā + Āᵀ S̄ + S̄ G Gᵀ S̄ − C₁ᵀ Ψ C₁`` forward with
    :func:`scipy.integrate.solve_ivp` (Radau, relative tolerance ``tol``) on the complement of ``Ŵ*``,
    where ``S(t) B̄ = 0`` holds for every t (Prop. 9.2), and returns ``S(t) = Γ₁ᵀ S̄(t) Γ₁`` (len(t) x n x n).

    ``S0`` (n x n, default 0 = PATH (9.41)) enters as ``S̄(0) = Γ₁ S0 Γ₁ᵀ``; Murray's boundary condition
    (4.50) ``S(t0+) = Π₀ − Π₀ B̄ (B̄ᵀ Π₀ B̄)⁻¹ B̄ᵀ Π₀`` with ``Π₀ > 0`` is the other natural choice.  Unstable
    zero directions are not removed here: ``S(t) ν → 0`` as t → ∞ (PATH Theorem 9.4).  A *stable* zero
    direction ν of ``(C, A, F̂)`` is an exactly uncoupled mode of (9.77) on which ``S = 0`` is an
    (unstable) equilibrium: from ``S(0) = 0`` it stays in ``Ker S(t)`` for all t, whereas from any
    ``S(0) > 0`` on it (e.g. (4.50)) ``S(t)`` converges to the stabilizing solution of :func:`goh_riccati`.

    Parameters
    ----------
    A, C : (n, n) and (p, n) arrays
        Plant matrices (continuous time).
    F_hat : (n, k) array
        ``F̂``, the complementary fault direction.
    t : sequence of float
        Nondecreasing output times ≥ 0 [s] (the equation starts at 0).
    V, Q : float or (p, p) array
        Noise weight ``V = V̄/γ`` (positive definite) and output weight, as in :func:`goh_riccati`.
    S0 : (n, n) array, optional
        Initial value (default 0, PATH (9.41)).
    projector : (p, p) array, optional
        ``Ĥ``; default the orthogonal projector annihilating ``C Ŵ*``.
    rtol : float, optional
        Rank tolerance of the subspace computations.
    tol : float
        Relative tolerance of the integration (default 1e-10).

    Returns
    -------
    numpy.ndarray
        ``S(t)``, shape (len(t), n, n).

    Raises
    ------
    ParameterError
        ``t`` not a nondecreasing 1-D sequence of times ≥ 0 (or a bad weight).
    DesignError
        Algorithm 4.1 fails, or the integration fails.

    Examples
    --------
    From ``S(0) = 0`` to the steady state of :func:`goh_riccati`:

    >>> from fdikit.plants.white_speyer import white_speyer
    >>> m = white_speyer("stable-extra-zero")
    >>> S = goh_riccati_transient(m.A, m.C, m.Bf[:, [1]], [0.0, 5.0], V=1.0, Q=0.002, tol=1e-6)
    >>> Sinf = goh_riccati(m.A, m.C, m.Bf[:, [1]], V=1.0, Q=0.002).S
    >>> S.shape, bool(np.abs(S[-1] - Sinf).max() < 1e-6 * np.abs(Sinf).max())
    ((2, 3, 3), True)

    References
    ----------
    Douglas et al. 1996, §9.3.2, (9.41), Prop. 9.2, and §9.5, (9.77)–(9.78); Murray 2012, §4.2.3, (4.50).
    """
    A, C, F, Vw, Qw, Vi, goh, H, Hb = _prepare(A, C, F_hat, V, Q, projector, rtol)
    n, W = A.shape[0], goh.invariant_subspace
    Gam, n1 = _split(W, n)
    G1 = Gam[:n1]
    CB = C @ goh.B_tilde
    Xi = np.linalg.inv(CB.T @ Vi @ CB) if goh.B_tilde.shape[1] else np.zeros((0, 0))
    Abar = G1 @ (A - goh.B_hat @ Xi @ CB.T @ Vi @ C) @ G1.T
    GG = G1 @ goh.B_hat @ Xi @ goh.B_hat.T @ G1.T
    C1 = C @ G1.T
    q = C1.T @ (Hb.T @ Vi @ Hb - H @ Qw @ H) @ C1

    def rhs(_, s):
        Sb = s.reshape(n1, n1)
        return (-(Sb @ Abar + Abar.T @ Sb + Sb @ GG @ Sb - q)).ravel()

    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or np.any(t < 0) or np.any(np.diff(t) < 0):
        raise ParameterError("t must be a nondecreasing 1-D sequence of times ≥ 0 (the equation starts at t0 = 0)")
    Sb0 = np.zeros((n1, n1)) if S0 is None else G1 @ validate.as_matrix("S0", S0, (n, n)) @ G1.T
    sol = solve_ivp(rhs, (0.0, float(t[-1]) if t.size else 0.0), Sb0.ravel(), method="Radau", t_eval=t,
                    rtol=tol, atol=tol * max(np.abs(q).max(), _EPS))
    if not sol.success:
        raise DesignError(f"integration of the reduced Goh Riccati equation failed: {sol.message}")
    out = np.empty((t.size, n, n))
    for k in range(t.size):
        Sb = sol.y[:, k].reshape(n1, n1)
        out[k] = G1.T @ ((Sb + Sb.T) / 2) @ G1
    return out
