"""Approximate model matching by the nullspace method: ``ammsyn`` (Varga 2017, §5.6, Procedure AMMS).

The approximate model-matching problem (AMMP) asks for a proper stable ``Q`` on ``[u; y]`` that decouples the
controls and disturbances exactly and makes the faults-and-noise part of its internal form close to an updated
reference, in the H∞ or the H2 norm:

    Q [Gu Gd; I 0] = 0,     γ = ‖Q [Gf Gw; 0 0] − M [M_rf M_rw]‖ = min,

with ``M`` diagonal, stable and invertible (``M = I`` when that is possible; ``M_rw = 0`` when the reference has
no noise group: noise attenuation).  With ``M_r = I`` from the faults this is H∞/H2 fault estimation.  A reference
with a control or disturbance group has that group matched approximately too, instead of decoupled (the
reference's ``weakfdi`` path): the problem is solved on a model whose faults are the matched groups, with the
controls read as outputs when they are matched.

How fdikit solves it (the reference's steps, with its own tools):

1. ``Q₁``: the proper nullspace basis of ``[Gu Gd; I 0]`` (:func:`~fdikit.design.nullspace.basis.left_nullspace`,
   poles at the default stability degree) or the observer basis ``[−Gu I]``, ``R = Q₁ [Gf Gw; 0 0]``; when ``R``
   lacks full row rank, the first basis rows (ascending degree) that keep its rank (the reference reduces to
   ``rdim`` rows here instead); a ``selection`` as a least-degree cover
   (:func:`~fdikit.design.nullspace.matching_basis.matching_rows`).
2. ``R = R_o R_i`` with ``R_i`` co-inner (``R_i R_i~ = I``) and ``R_o`` (quasi-)co-outer: the co-inner factor of
   ``T R`` after the row operations that remove the zeros at infinity and on the boundary
   (:func:`~fdikit.design.nullspace.zero_steps.remove_boundary_zeros`; ``T R_o`` is outer, so the co-inner factor is
   that of ``R``).  The problem is non-standard when there were such zeros.
3. The least-distance problem ``min ‖Y R_i − F‖`` over stable ``Y``, ``F = [M_rf M_rw]`` (the reference's
   ``glinfldp`` on ``F R_i~``; since ``R_i`` is inner the two are the same): an H∞ (or H2) model-matching problem
   with measurement ``R_i v`` whose ``D`` has full row rank (``R_i`` is co-inner), solved by SLICOT's H∞ ``SB10AD``
   (γ-iteration to ``reltol``) or H2 ``SB10HD`` (through slycot).  Discrete H∞ problems are solved on the
   bilinear image ``z = (1 + s)/(1 − s)``, which keeps H∞ norms; discrete H2 by the causal projection
   ``Y = [F R_i~]₊``, which SLICOT lacks.  In H2 a continuous ``F`` whose ``D`` cannot be matched
   is first multiplied by ``M₀ = a/(s + a)``, ``a = −sdeg`` (as the reference does).
4. ``Q`` with ``Q G_e = M [0 0 Y R_i]``: :func:`~fdikit.design.nullspace.model_matching.emmsyn` on that (stable)
   target; in the standard case ``Q = Y R_o⁻¹ Q₁`` and ``M = I``, otherwise the least-degree ``M`` makes the
   improper or unstable ``Y R_o⁻¹ Q₁`` proper and stable (the reference's ``glcf`` with ``mininf``, ``mindeg``).

``gamma_opt0`` is the optimum of step 3, ``gamma_opt`` that of the problem with ``M F``, ``gamma_sub`` the achieved
``‖Q G_e − M M_r‖``; ``gamma_sub = gamma_opt`` up to ``reltol`` in the standard case.

Why by hand: the steps are the reference's; SLICOT solves the least-distance problem, and no Python library has
the nullspace, factorisation and updating steps around it.

References
----------
Varga (2017), §5.6 (AMMP, Procedure AMMS), §7.9 (co-outer–co-inner factorisation); Varga (2011) (the integrated
H∞ algorithm, cited by the reference); fdtools (``ammsyn``, ``glinfldp``); SLICOT ``SB10AD``, ``SB10HD``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.design.nullspace.basis import default_sdeg, minimal_realization
from fdikit.design.nullspace.matching_basis import matching_rows
from fdikit.design.nullspace.model_matching import (
    ModelMatchingBankDesign,
    ModelMatchingDesign,
    emmsyn,
    reference_bank,
    reference_columns,
    reference_model,
    updated_reference,
)
from fdikit.design.nullspace.nehari_ldp import distance_error, two_block_distance
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.protocols import FieldReport
from fdikit.residuals import ResidualGenerator

__all__ = ["ApproximateMatchingDesign", "ammsyn", "least_distance"]

@dataclass(frozen=True, eq=False)
class ApproximateMatchingDesign(FieldReport):
    """An approximate model-matching filter (``ammsyn``) and its report.

    Attributes
    ----------
    generator : ResidualGenerator
        The filter ``Q`` (inputs ``[u; y]``), one residual per output of the reference, stable and proper.
    target : FaultModel
        The updated reference ``M M_r``.
    updating : tuple of (numpy.ndarray, numpy.ndarray)
        ``M_i = num / den`` per residual (``λ``, highest power first); ``M₀`` of the H2 case included.
    reference : FaultModel
        ``M_r`` asked for.
    norm : str
        ``'inf'`` or ``'2'``.
    nonstandard : bool
        Whether ``R = Q₁ [Gf Gw; 0]`` had zeros at infinity or on the stability boundary.
    gamma_opt0, gamma_opt, gamma_sub : float
        The optimal distance of the original problem (of ``M₀ M_r`` in the H2 case with ``M₀``), that of the
        updated problem (``M M_r``), and the distance achieved (reference ``info.gammaopt0``, ``gammaopt``,
        ``gammasub``).
    exact : ModelMatchingDesign or None
        Non-standard case: the ``emmsyn`` design of the last step (``Q G_e = M [0 0 Y R_i]``); None otherwise.
    poles : numpy.ndarray
        The filter eigenvalues.

    Examples
    --------
    Estimating a sensor fault ``f`` from ``y = f + w`` (``G_f = 1``, ``G_w = 1/(s+1)``): the optimum over stable
    ``q`` of ``‖[q − 1, q/(s+1)]‖∞`` is reached at a constant ``q``, ``γ = 1/√2`` (``q = 1/2``):

    >>> m = FaultModel([[-1.0]], [[1.0]], Bw=[[1.0]], Df=[[1.0]])
    >>> d = ammsyn(m, {"f": [[1.0]]})
    >>> round(d.gamma_opt0, 4), d.nonstandard
    (0.7071, False)

    References
    ----------
    Varga (2017), §5.6, Procedure AMMS; fdtools (``ammsyn``).
    """

    generator: ResidualGenerator
    target: FaultModel
    updating: tuple[tuple[np.ndarray, np.ndarray], ...]
    reference: FaultModel
    norm: str
    nonstandard: bool
    gamma_opt0: float
    gamma_opt: float
    gamma_sub: float
    exact: ModelMatchingDesign | None
    poles: np.ndarray

    REPORT = ("norm", "nonstandard", "gamma_opt0", "gamma_opt", "gamma_sub", "updating", "poles")


def _bilinear(sys, to_continuous: bool):
    """The bilinear image of ``(A, B, C, D)``: ``G(z)`` at ``z = (1+s)/(1−s)``, or back at ``s = (z−1)/(z+1)``."""
    from fdikit.design.nullspace.wiener_hopf import moebius

    return moebius(*sys, 1.0, 1.0, -1.0, 1.0) if to_continuous else moebius(*sys, 1.0, -1.0, 1.0, 1.0)


def _plant(inner, F, Y0=None):
    """Generalised plant of ``min ‖Y R_i − F‖``: inputs ``[v; Y's output]``, outputs ``[z; R_i v]``."""
    import scipy.linalg

    A1, B1, C1, D1 = inner
    A2, B2, C2, D2 = F
    q, r, m = D2.shape[0], D1.shape[0], D1.shape[1]
    n1, n2 = A1.shape[0], A2.shape[0]
    Y0 = np.zeros((q, r)) if Y0 is None else Y0
    A = scipy.linalg.block_diag(A1, A2)
    B = np.block([[B1, np.zeros((n1, q))], [B2, np.zeros((n2, q))]])
    C = np.block([[Y0 @ C1, -C2], [C1, np.zeros((r, n2))]])
    D = np.block([[Y0 @ D1 - D2, np.eye(q)], [D1, np.zeros((r, q))]])
    return A, B.reshape(n1 + n2, m + q), C.reshape(q + r, n1 + n2), D


def _hinf_bisection(plant, q: int, r: int, top: float, loop_norm, reltol: float):
    """Bisection on γ: SB10AD's suboptimal controller (``job = 4``) accepted when ``loop_norm(K)`` is below γ.

    SB10AD's own γ-iteration (``job = 1``) stops on the closed-loop stability, which here (``B₂ = 0``, a stable
    plant) never fails, and went below the optimum on Example 5.14 (its controller missed the γ it returned).
    ``top = ‖F‖∞`` (``Y = 0``) starts it.
    """
    import slycot

    A, B, C, D = plant
    n, m_all = A.shape[0], B.shape[1]
    if top == 0.0:                     # a zero reference: Y = 0 is optimal
        return 0.0, (np.zeros((0, 0)), np.zeros((0, r)), np.zeros((q, 0)), np.zeros((q, r)))
    hi, floor = 1.001 * top + 1e-12, 1e-9 * top
    K_hi = None
    lo = 0.0
    for _ in range(200):
        g = 0.5 * (lo + hi) if K_hi is not None else hi
        try:
            K = slycot.sb10ad(n, m_all, q + r, q, r, g, A, B, C, D, job=4)[1:5]
            ok = loop_norm(K) <= g * (1 + 1e-9)
        except (ValueError, ArithmeticError):
            ok = False
        if ok:
            hi, K_hi = g, K
        elif K_hi is None:
            raise DesignError(f"SB10AD found no controller at γ = {g:g} ≥ ‖F‖∞; the least-distance problem is "
                              "ill-posed (check that the reference is stable)")
        else:
            lo = g
        if K_hi is not None and (hi - lo <= reltol * hi or hi <= floor):
            break
    return hi, K_hi


def _causal_projection(F, inner):
    """``[F R_i~]₊`` of two stable discrete systems: ``(A_F, B_F D_iᵀ + A_F X C_iᵀ, C_F, D_F D_iᵀ + C_F X C_iᵀ)``.

    ``F(z) R_i(1/z)ᵀ`` has the coefficients ``Σ_b f[b + j] r[b]ᵀ`` at ``z⁻ʲ``; for ``j ≥ 0`` they are those of the
    realisation above with ``X = A_F X A_iᵀ + B_F B_iᵀ`` (a Stein equation, solved on its Kronecker form).  With
    ``R_i R_i~ = I`` it is the H2-optimal ``Y`` of ``min ‖Y R_i − F‖₂``.
    """
    A1, B1, C1, D1 = F
    A2, B2, C2, D2 = inner
    n1, n2 = A1.shape[0], A2.shape[0]
    rhs = B1 @ B2.T
    X = np.linalg.solve(np.eye(n1 * n2) - np.kron(A2, A1), rhs.reshape(-1, order="F")).reshape(
        (n1, n2), order="F") if n1 and n2 else np.zeros((n1, n2))
    return A1, B1 @ D2.T + A1 @ X @ C2.T, C1, D1 @ D2.T + C1 @ X @ C2.T


def least_distance(inner, F, *, norm: str = "inf", dt: float | None = None, reltol: float = 1e-4,
                   ldp: str = "central"):
    """``Y`` stable minimising ``‖Y R_i − F‖`` (H∞ or H2) for a co-inner ``R_i`` and a stable ``F``.

    Parameters
    ----------
    inner : tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``R_i`` (``r × m``, stable, ``R_i R_i~ = I``).
    F : tuple of numpy.ndarray
        ``(A, B, C, D)`` of ``F`` (``q × m``, stable).
    norm : {'inf', '2'}, default 'inf'
        The norm; continuous ``'2'`` needs ``F`` matchable at infinity (a finite H2 distance).
    dt : float or None
        Sample time (discrete H∞ is solved on the bilinear image, discrete H2 by the causal projection
        ``Y = [F R_i~]₊``).
    reltol : float, default 1e-4
        Relative accuracy of the H∞ γ-iteration.
    ldp : {'central', 'nehari'}, default 'central'
        The H∞ solver: the central controller of the equivalent H∞ plant (SLICOT ``SB10AD``, bisected on the
        achieved distance), or the reference's Chu–Doyle–Lee γ-iteration with an optimal Nehari step
        (:func:`~fdikit.design.nullspace.nehari_ldp.two_block_distance`).  Both reach the optimal ``γ``; where the
        optimal ``Y`` is not unique they return different ones (``'nehari'`` the reference's).

    Returns
    -------
    tuple
        ``((A, B, C, D) of Y, γ)``: the controller and the optimal distance (H∞: SB10AD's estimate; H2: the
        distance of ``Y``).

    Raises
    ------
    DesignError
        When SLICOT fails (an assumption of SB10AD/SB10HD violated, e.g. ``F`` unstable).

    Examples
    --------
    ``R_i = [1/√2, 1/√2]`` (static), ``F = [1, 0]``: ``Y = 1/√2``, ``γ = 1/√2``.

    >>> Y, g = least_distance((np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), np.full((1, 2), 0.5 ** 0.5)),
    ...                       (np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), np.array([[1.0, 0.0]])))
    >>> round(float(Y[3][0, 0]), 9), round(g, 9)
    (0.707106781, 0.707106781)

    References
    ----------
    Varga (2017), §5.6 (the least-distance problem of Procedure AMMS); fdtools (``glinfldp``); SLICOT ``SB10AD``,
    ``SB10HD``.
    """
    import slycot

    inner = tuple(np.atleast_2d(np.asarray(M, dtype=float)) for M in inner)
    F = tuple(np.atleast_2d(np.asarray(M, dtype=float)) for M in F)
    q, r = F[3].shape[0], inner[3].shape[0]
    if ldp not in ("central", "nehari"):
        raise ParameterError(f"ldp must be 'central' or 'nehari', got {ldp!r}")
    if norm != "inf" and dt is not None:                  # discrete H2: Y = [F R_i~]₊, the causal projection
        Y = _causal_projection(F, inner)
        return Y, _norm(distance_error(inner, Y, F), "2", dt)
    Y0 = F[3] @ inner[3].T if dt is None else None
    if dt is not None:
        inner, F = _bilinear(inner, True), _bilinear(F, True)
        Y0 = F[3] @ inner[3].T
    A, B, C, D = _plant(inner, F, Y0)
    n = A.shape[0]
    if n == 0:        # static: Y = F Rᵢᵀ, the distance of the part of F orthogonal to the rows of Rᵢ
        Y = (np.zeros((0, 0)), np.zeros((0, r)), np.zeros((q, 0)), Y0)
        g = float(np.linalg.norm(D[:q, : D.shape[1] - q], 2)) if norm == "inf" else (
            0.0 if np.allclose(D[:q, : D.shape[1] - q], 0) else float("inf"))
        return (Y if dt is None else _bilinear(Y, False)), g
    m_all = B.shape[1]
    if norm == "inf" and ldp == "nehari":
        Y, g = two_block_distance(inner, F, reltol=reltol)
        return (Y if dt is None else _bilinear(Y, False)), float(g)
    try:
        if norm == "inf":
            # P₂₂ = 0: the loop closed by K is the series connection (K + Y₀) R_i − F
            g, (Ak, Bk, Ck, Dk) = _hinf_bisection(
                (A, B, C, D), q, r, _norm(F), lambda K: _norm(distance_error(inner, (*K[:3], K[3] + Y0), F)), reltol)
        else:
            if np.abs(D[:q, : m_all - q]).max(initial=0.0) > 1e-10 * max(1.0, np.abs(F[3]).max(initial=0.0)):
                raise DesignError("the H2 distance is infinite: F is not matched at infinity; multiply it by a "
                                  "low-pass (ammsyn does, with M₀ = a/(s + a))")
            Ak, Bk, Ck, Dk = slycot.sb10hd(n, m_all, q + r, q, r, A, B, C, D)[:4]
    except (ValueError, ArithmeticError) as err:
        raise DesignError(f"SLICOT could not solve the least-distance problem: {err}") from err
    Y = (Ak, Bk, Ck, Dk + Y0)
    if norm != "inf":
        g = _norm(distance_error(inner, Y, F), "2")
    return (Y if dt is None else _bilinear(Y, False)), float(g)


def _target_columns(model: FaultModel, ref: FaultModel, groups):
    """``F = [M_r,g … M_rw]`` over the matched ``groups`` and the noise (zero where ``M_r`` lacks one)."""
    B, D = reference_columns(ref, model, tuple(groups) + ("w",))
    return ref.A, B, ref.C, D


def _matching_model(model: FaultModel, groups) -> FaultModel:
    """The model the problem is solved on: the matched ``groups`` as its faults, the others decoupled.

    Matched controls (a reference with ``M_ru``) are also measured: ``[y; u]`` become the outputs and the model has
    no controls, so the nullspace decouples only what the reference lacks (the reference's ``weakfdi`` path).
    """
    if groups == ("f",):
        return model
    names = sum((model.inputs[g] for g in groups), ())
    Bf, Df = np.hstack([model.b(g) for g in groups]), np.hstack([model.d(g) for g in groups])
    A, C, dist = model.A, model.C, () if "d" in groups else model.disturbances
    Bd, Dd = (np.zeros((model.n, 0)), np.zeros((model.p, 0))) if "d" in groups else (model.b("d"), model.d("d"))
    Bu, Du, ctrl, outs = model.b("u"), model.d("u"), model.controls, model.outputs
    Bw, Dw = model.b("w"), model.d("w")
    if "u" in groups:                       # u read as outputs: [y; u] = [G; I 0 …] [u; d; f; w]
        mu = len(model.controls)
        C = np.vstack([C, np.zeros((mu, model.n))])
        eye_u = np.hstack([np.eye(mu), np.zeros((mu, Bf.shape[1] - mu))])
        Df = np.vstack([Df, eye_u])
        Dd, Dw = np.vstack([Dd, np.zeros((mu, Dd.shape[1]))]), np.vstack([Dw, np.zeros((mu, Dw.shape[1]))])
        Bu, Du, ctrl = np.zeros((model.n, 0)), np.zeros((model.p + mu, 0)), ()
        outs = model.outputs + tuple(f"{c}__measured" for c in model.controls)
    return FaultModel(A, C, Bu=Bu, Du=Du, Bd=Bd, Dd=Dd, Bf=Bf, Df=Df, Bw=Bw, Dw=Dw, controls=ctrl,
                      disturbances=dist, faults=names, noise=model.noise, outputs=outs, dt=model.dt)


def _on_model(gen: ResidualGenerator, model: FaultModel, groups) -> ResidualGenerator:
    """A generator of the matching model as one of ``model`` (matched controls: its ``[y; u]`` back to ``[u; y]``)."""
    if "u" not in groups:
        return gen
    p = model.p
    B, D = np.hstack([gen.B[:, p:], gen.B[:, :p]]), np.hstack([gen.D[:, p:], gen.D[:, :p]])
    return ResidualGenerator(gen.A, B, gen.C, D, controls=model.controls, outputs=model.outputs,
                             residuals=gen.residuals, dt=model.dt)


def _fw_model(sys, model: FaultModel, names) -> FaultModel:
    """``(A, B, C, D)`` on ``[f; w]`` as a FaultModel (a hidden state when it is static: models need one)."""
    A, B, C, D = sys
    if A.shape[0] == 0:
        A, B, C = np.array([[-1.0 if model.dt is None else 0.0]]), np.zeros((1, D.shape[1])), np.zeros((D.shape[0], 1))
    nf = len(model.faults)
    return FaultModel(A, C, Bf=B[:, :nf], Df=D[:, :nf], Bw=B[:, nf:], Dw=D[:, nf:], faults=model.faults,
                      noise=model.noise, outputs=names, dt=model.dt)


def _norm(sys, which: str = "inf", dt: float | None = None) -> float:
    """H∞ or H2 norm of a stable realisation ``(A, B, C, D)`` (python-control/SLICOT; ``inf`` when unstable)."""
    from fdikit.analysis.channels import Channel, h2_norm, hinf_norm

    ch = Channel(*sys, dt)
    return float(hinf_norm(ch)[0] if which == "inf" else h2_norm(ch))


def _low_pass(F, a: float):
    """``M₀ F`` with ``M₀ = a/(s + a)`` on every output (continuous H2 with an unmatched ``D``)."""
    from fdikit.design.nullspace.factorization import series

    q = F[3].shape[0]
    return series(F, (-a * np.eye(q), a * np.eye(q), np.eye(q), np.zeros((q, q))))


def ammsyn(model: FaultModel, reference, *, norm: str = "inf", names: Sequence[str] | None = None, selection=None,
           nullspace: bool = True, regmin: bool = True, poles: Sequence[complex] | None = None,
           sdeg: float | None = None, smarg: float | None = None,
           normalize: str = "infnorm", reltol: float = 1e-4, ldp: str = "central",
           tol: float = 1e-7) -> ApproximateMatchingDesign | ModelMatchingBankDesign:
    """Approximate model matching in the H∞ or H2 norm (Procedure AMMS).

    Parameters
    ----------
    model : FaultModel
        The plant (continuous or discrete).
    reference : FaultModel, mapping, or a sequence of them
        ``M_r``, stable: an internal form or a static ``{group: matrix}``.  The faults and noise are matched (a group
        it lacks: zero); the controls and disturbances are decoupled exactly unless ``M_r`` has that group, which is
        then matched too.  A sequence gives a bank (``ModelMatchingBankDesign``), one filter per reference.
    norm : {'inf', '2'}, default 'inf'
        H∞ (the reference's default) or H2 (``H2syn = true``).
    names : sequence of str, optional
        Residual names (default the reference's outputs; ``r<i>`` for a static reference).
    selection : array_like, optional
        ``H``: use the rows ``H N`` of the nullspace basis only (the reference's ``HDesign``): ``(k, len(basis.rows))``
        in fdikit's minimal basis coordinates, ``(k, p)`` on the observer basis; full row rank.  Default the basis
        rows that keep the rank of ``R``.
    nullspace : bool, default True
        The minimal proper nullspace basis, or (False) the observer basis ``[−Gu I]``, ``R = [Gf Gw]`` (the
        reference's ``nullspace = false``; only when no disturbance is decoupled).
    regmin : bool, default True
        Least-degree annihilator ``(H + Y) N``, ``Y`` strictly proper (the reference's ``regmin`` and its
        ``glmcover1``; :mod:`~fdikit.design.nullspace.matching_basis`); False: ``H N`` as it stands.
    poles, sdeg, smarg, normalize
        The updating factor of the non-standard case, as in :func:`~fdikit.design.nullspace.model_matching.emmsyn`
        (``normalize`` default ``'infnorm'``, the reference's).
    reltol : float, default 1e-4
        Relative accuracy of the H∞ γ-iteration.
    ldp : {'central', 'nehari'}, default 'central'
        The H∞ least-distance solver (:func:`least_distance`): ``'nehari'`` is the reference's route, which returns
        the reference's filter where the optimal one is not unique (Example 5.6c).
    tol : float, default 1e-7
        Rank and zero decisions.

    Returns
    -------
    ApproximateMatchingDesign or ModelMatchingBankDesign

    Raises
    ------
    DesignError
        An empty nullspace, nothing to match, an unstable reference, a SLICOT failure.
    ParameterError
        Bad options or a reference that does not fit the model.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0]], Bw=[[1.0]], Df=[[1.0]])
    >>> d = ammsyn(m, {"f": [[1.0]]})
    >>> round(d.gamma_sub, 4), round(d.gamma_opt0, 4)
    (0.7071, 0.7071)

    References
    ----------
    Varga (2017), §5.6, Procedure AMMS; fdtools (``ammsyn``).
    """
    from fdikit.analysis.channels import minimal_channel
    from fdikit.design.nullspace.factorization import series
    from fdikit.design.nullspace.zero_steps import remove_boundary_zeros

    which = {"inf": "inf", "2": "2", np.inf: "inf", 2: "2"}.get(norm.lower() if isinstance(norm, str) else norm)
    if which is None:
        raise ParameterError(f"norm must be 'inf' (H∞) or 2 (H2), got {norm!r}")
    if not (np.isfinite(reltol) and 0 < reltol < 1):
        raise ParameterError(f"reltol must be in (0, 1), got {reltol}")
    if isinstance(reference, (list, tuple)):
        return reference_bank(model, reference, names, lambda r, nm: ammsyn(
            model, r, norm=norm, names=nm, selection=selection, nullspace=nullspace, regmin=regmin, poles=poles,
            sdeg=sdeg, smarg=smarg, normalize=normalize, reltol=reltol, ldp=ldp, tol=tol))
    ref = reference_model(model, reference, names)
    groups = tuple(g for g in ("u", "d") if len(ref.inputs[g])) + ("f",)
    plant = _matching_model(model, groups)
    ev = np.linalg.eigvals(minimal_channel(ref).A)
    if ev.size and np.max(ev.real if ref.dt is None else np.abs(ev)) >= (0.0 if ref.dt is None else 1.0):
        raise DesignError(f"the reference model has unstable poles {np.round(ev, 6).tolist()}; the model-matching "
                          "error has no finite norm: give a stable reference")
    if names is None and not isinstance(reference, FaultModel):
        names = tuple(f"r{i}" for i in range(ref.p))
    names = tuple(ref.outputs if names is None else names)
    Aj, Bq, Br, Cj, Dq, Dr = matching_rows(plant, selection, nullspace=nullspace, regmin=regmin, tol=tol)
    if (np.linalg.eigvals(Aj).real if model.dt is None else np.abs(np.linalg.eigvals(Aj)) - 1).max(initial=-1) >= 0:
        raise DesignError("R = Q₁ [Gf Gw; 0] is unstable: the plant has unstable modes that the faults or the noise "
                          "excite and the decoupled residuals see; stabilise them first")
    _, _, steps, g1 = remove_boundary_zeros(Aj, Br, Cj, Dr, model.dt, tol=tol)
    inner = g1.inner
    F = _target_columns(model, ref, groups)
    s0 = default_sdeg(model.dt) if sdeg is None else float(sdeg)
    M0 = None
    if which == "2" and model.dt is None:
        unmatched = F[3] - F[3] @ inner[3].T @ inner[3]
        if np.abs(unmatched).max(initial=0.0) > tol * max(1.0, np.abs(F[3]).max(initial=0.0)):
            M0 = (np.array([-s0]), np.array([1.0, -s0]))
            F = _low_pass(F, -s0)
    Y, g0 = least_distance(inner, F, norm=which, dt=model.dt, reltol=reltol, ldp=ldp)
    q = ref.p
    if not steps:               # standard: Q = Y R_o⁻¹ Q₁, proper and stable, M = I
        Ao, Bo, Co, Do = g1.outer                 # R_o = (A, K R_h, C, R_h) on R's state space
        K, Rhi = Bo @ np.linalg.inv(Do), np.linalg.inv(Do)
        X = (Aj - K @ Cj, Bq - K @ Dq, Rhi @ Cj, Rhi @ Dq)           # R_o⁻¹ Q₁, stable
        gen = ResidualGenerator(*series(X, Y), controls=plant.controls, outputs=plant.outputs, residuals=names,
                                dt=model.dt)
        exact, M1 = None, ((np.ones(1), np.ones(1)),) * q
    else:                       # non-standard: Q with Q G_e = M₁ [0 0 Y R_i], M₁ of least degree
        fit = _fw_model(minimal_realization(*series(inner, Y)), plant, names)
        exact = emmsyn(plant, fit, names=names, poles=poles, sdeg=sdeg, smarg=smarg, normalize=normalize, tol=tol)
        gen, M1 = exact.generator, exact.updating
    upd = M1 if M0 is None else tuple((np.polymul(num, M0[0]), np.polymul(den, M0[1])) for num, den in M1)
    target = updated_reference(ref, upd)
    if all(num.tolist() == den.tolist() for num, den in M1):
        g_opt = g0
    else:
        g_opt = least_distance(inner, _target_columns(model, target, groups), norm=which, dt=model.dt,
                               reltol=reltol, ldp=ldp)[1]
    # achieved: ‖M₁ (Y R_i − F)‖ (F with M₀), since Q [Gf Gw; 0] = M₁ Y R_i exactly (by construction, or emmsyn's
    # check); evaluated on that small stable realisation, not on the internal form, whose plant modes cancel only
    # to rounding (a minimal realisation of it found a peak of 42 instead of 1.00002 on the PATH model)
    E = _fw_model(distance_error(inner, Y, F), plant, names)
    T = updated_reference(E, M1)
    g_sub = _norm((T.A, T.B, T.C, T.D), which, model.dt)
    gen = _on_model(gen, model, groups)
    return ApproximateMatchingDesign(gen, target, upd, ref, which, bool(steps), float(g0), float(g_opt), g_sub,
                                     exact, np.linalg.eigvals(gen.A) if gen.n else np.zeros(0), model=model)
