"""The left annihilator a model-matching synthesis starts from: ``[Q₁ R]`` on one state space (``ammsyn`` step 1).

``Q₁`` decouples the controls and the disturbances (``Q₁ [Gu Gd; I 0] = 0``) and ``R = Q₁ [Gf Gw; 0]`` is what the
matching acts on.  Two bases of that nullspace, as in the reference (``nullspace = true / false``):

* the minimal proper basis ``N`` (:func:`~fdikit.design.nullspace.basis.left_nullspace`, row ``i`` over its own
  stable denominator of degree ``ν_i``), the default;
* the observer basis ``N = [−Gu I]`` on ``[u; y]`` (the plant's own state; only without disturbances), with
  ``R = [Gf Gw]``.

A ``selection`` ``H`` (the reference's ``HDesign``) combines the rows of the chosen basis.  With ``regmin`` (the
reference's default) the annihilator is a least-degree one among ``X = (H + Y(λ)) N`` with ``Y`` strictly proper
(the reference's minimal dynamic cover, ``glmcover1``).  Writing ``X = a(μ) P(μ) / φ`` with ``P`` the minimal
polynomial basis (degrees ``ν_i``, leading ``y``-coefficients ``L_i``), ``X`` is proper of degree ``k`` when
``deg a_i ≤ k − ν_i``, and ``(H + Y)(∞) = H`` fixes what ``X`` does at infinity:

* minimal basis: ``lc(a_i) = H_i``, so ``k = max{ν_i : H_i ≠ 0}``, reached by ``Σ H_i μ^(k−ν_i) P_i`` over one
  denominator of degree ``k`` (a ``selection`` of the minimal basis is already of least degree);
* observer basis: ``X``'s ``y``-part at infinity is ``h`` (``N_y = I``), i.e. ``Σ_{ν_i ≤ k} c_i L_i = h``; ``k`` is
  the least degree whose ``L_i`` span ``h`` (the ``L_i`` of a minimal basis of ``[Gu; I]`` span all of ``y``,
  since ``P`` is row reduced and ``Gu`` proper), and ``X = Σ c_i μ^(k−ν_i) P_i``.  A degree whose row would lose
  the rank of ``R`` is passed over (the reference's admissibility check after ``glmcover1``).

When the least degree leaves a free part (lower coefficients of ``a_i``, or a ``c`` that is not unique) fdikit sets
it to zero (``c`` of least norm); the reference's ``glmcover1`` makes its own choice, which can give another ``γ``.
Without ``regmin``: ``H N`` as it stands (order ``Σ ν_i`` of the combined rows, or the plant order).

Why by hand: no Python library computes nullspace bases of rational matrices or their dynamic covers.

References
----------
Varga (2017), §5.6 (Procedure AMMS, step 1), §7.4 (minimal polynomial bases, predictable degree), §7.5 (minimal
dynamic covers); fdtools (``ammsyn``: ``nullspace``, ``regmin``, ``HDesign``; ``glmcover1``).
"""

from __future__ import annotations

import numpy as np

from fdikit.design.nullspace.basis import NullspaceBasis, denominator, left_nullspace, minimal_realization, realize_rows
from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel

__all__ = ["matching_rows"]

_POINTS = (0.613 + 0.791j, -0.377 + 1.93j)


def _cover(basis: NullspaceBasis, h: np.ndarray, mu: int, tol: float):
    """The rows ``Σ c_i μ^(k−ν_i) P_i`` whose ``y``-part at infinity is ``h``, by ascending degree ``k``."""
    nu = np.array(basis.degrees)
    L = np.array([r[-1, mu:] for r in basis.rows])              # leading y-coefficients, one per basis row
    for k in sorted({int(v) for v in nu}):
        S = np.flatnonzero(nu <= k)
        c = np.linalg.lstsq(L[S].T, h, rcond=None)[0]
        if np.linalg.norm(L[S].T @ c - h) > tol * max(np.linalg.norm(h), 1e-300):
            continue
        row = np.zeros((k + 1, basis.rows[0].shape[1]))
        for ci, i in zip(c, S):
            row[k - nu[i]:] += ci * basis.rows[i]
        yield row


def matching_rows(model: FaultModel, selection=None, *, nullspace: bool = True, regmin: bool = True,
                  tol: float = 1e-7):
    """``[Q₁ R]`` on one minimal state space: ``(A, B_q, B_r, C, D_q, D_r)``, the rows of ``R`` scaled.

    Parameters
    ----------
    model : FaultModel
        The plant; its controls and disturbances are decoupled, its faults and noise make up ``R``.
    selection : array_like, optional
        ``H``, full row rank, one column per basis row (``len(left_nullspace(model).rows)`` for the minimal basis,
        ``model.p`` for the observer basis).  Default: the first basis rows that keep the rank of ``R``.
    nullspace : bool, default True
        The minimal proper basis (True) or the observer basis ``[−Gu I]`` (False; no disturbances allowed).
    regmin : bool, default True
        Least-degree rows ``(H + Y) N`` (see the module notes); False: ``H N``.
    tol : float, default 1e-7
        Relative tolerance of the rank and span decisions.

    Returns
    -------
    tuple of numpy.ndarray
        ``A, B_q, B_r, C, D_q, D_r``: ``Q₁`` reads ``[u; y]``, ``R = Q₁ [Gf Gw; 0]`` reads ``[f; w]``; the rows are
        scaled to comparable gains (a constant left factor, which changes neither the co-inner factor of ``R``
        nor the optimal distance).

    Raises
    ------
    DesignError
        An empty nullspace, nothing to match, or no admissible row.
    ParameterError
        A bad ``selection``, or ``nullspace=False`` with disturbances.

    Examples
    --------
    Example 5.6's plant (``p = 2``, one control): ``H = [1 1]`` on the observer basis has order 2 as it stands
    (poles −2 and −3) and order 1 as a least-degree cover:

    >>> import control as ct
    >>> s = ct.tf("s")
    >>> G = ct.ss(ct.tf([[[1, 1], [1, 1], [0]], [[1, 2], [0], [1]]], [[[1, 2], [1, 2], [1]], [[1, 3], [1], [1]]]))
    >>> m = FaultModel(G.A, G.C, Bu=G.B[:, :1], Du=G.D[:, :1], Bf=G.B[:, 1:], Df=G.D[:, 1:])
    >>> [matching_rows(m, [[1.0, 1.0]], nullspace=False, regmin=r)[0].shape[0] for r in (False, True)]
    [2, 1]

    References
    ----------
    Varga (2017), §5.6, §7.4, §7.5; fdtools (``ammsyn``, ``glmcover1``).
    """
    from fdikit.design.nullspace.factorization import transfer

    basis = left_nullspace(model)
    if not basis.rows:
        raise DesignError("the nullspace of [Gu Gd; I 0] is empty: no filter decouples the controls and the "
                          "disturbances, so no model matching is possible")
    if not (model.faults or model.noise):
        raise DesignError("the model has no fault or noise inputs: nothing to match")
    if not nullspace and model.disturbances:
        raise ParameterError("nullspace=False (the observer basis [−Gu I]) needs a model without disturbances: "
                             "their decoupling needs the nullspace basis (nullspace=True)")
    mu, p, n = len(model.controls), model.p, model.n
    Bfw, Dfw = np.hstack([model.b("f"), model.b("w")]), np.hstack([model.d("f"), model.d("w")])
    Bu, Du = model.b("u"), model.d("u")
    k_all = len(basis.rows) if nullspace else p

    def basis_at(lam):                                         # N(λ) on [u; y], numerators of the minimal basis
        if nullspace:
            return basis.evaluate(lam)
        return np.hstack([-transfer((model.A, Bu, model.C, Du), lam), np.eye(p)])

    def rank(H, lam) -> int:
        sv = np.linalg.svd(H @ basis_at(lam)[:, mu:] @ transfer((model.A, Bfw, model.C, Dfw), lam), compute_uv=False)
        return int(np.sum(sv > 1e-9 * max(sv[0], 1e-300))) if sv.size else 0

    if selection is None:
        chosen: list[int] = []
        for i in range(k_all):
            if min(rank(np.eye(k_all)[chosen + [i]], z * basis.scale) for z in _POINTS) == len(chosen) + 1:
                chosen.append(i)
        if not chosen:
            raise DesignError("no fault or noise input reaches the decoupled residuals: nothing to match")
        H = np.eye(k_all)[chosen]
    else:
        H = np.atleast_2d(np.asarray(selection, dtype=float))
        if H.shape[1] != k_all or not np.all(np.isfinite(H)) or np.linalg.matrix_rank(H) < H.shape[0]:
            what = f"basis row, degrees {list(basis.degrees)}" if nullspace else "output (observer basis [−Gu I])"
            raise ParameterError(f"selection must be a finite matrix of full row rank with {k_all} columns (one per "
                                 f"{what}), got shape {H.shape}")
    if not nullspace and not regmin:          # H [−Gu I] and H [Gf Gw] on the plant's state
        A, Bq, Br, C = model.A, np.hstack([-Bu, np.zeros((n, p))]), Bfw, H @ model.C
        Dq, Dr = np.hstack([-H @ Du, H]), H @ Dfw
    else:
        if not nullspace:                     # least-degree covers of the rows of H [−Gu I]
            def row_rank(trial, z) -> int:
                Nz = np.array([np.polynomial.polynomial.polyval(z, r) for r in trial])[:, mu:]
                sv = np.linalg.svd(Nz @ transfer((model.A, Bfw, model.C, Dfw), z * basis.scale), compute_uv=False)
                return int(np.sum(sv > 1e-9 * max(sv[0], 1e-300)))

            target = min(rank(H, z * basis.scale) for z in _POINTS)
            rows: list[np.ndarray] = []
            for h in H:
                need = min(len(rows) + 1, target)
                row = next((r for r in _cover(basis, h, mu, tol)
                            if min(row_rank([*rows, r], z) for z in _POINTS) >= need), None)
                if row is None:
                    raise DesignError(f"no least-degree row with the y-part {h.tolist()} at infinity keeps the rank "
                                      "of R; use regmin=False")
                rows.append(row)
            dens = [denominator(r.shape[0] - 1, None, None, model.dt) for r in rows]
        elif regmin or selection is None:     # the minimal basis: H N over one denominator per row of H
            rows = [basis.combined(h[None, np.flatnonzero(h)], np.flatnonzero(h))[0] for h in H]
            dens = [denominator(r.shape[0] - 1, None, None, model.dt) for r in rows]
        else:                                 # H applied to the basis rows over their own denominators
            rows = list(basis.rows)
            dens = [denominator(d, None, None, model.dt) for d in basis.degrees]
        Aq, Bq0, Cq, Dq0 = realize_rows(rows, dens, basis.scale)
        if nullspace and not regmin and selection is not None:
            Cq, Dq0 = H @ Cq, H @ Dq0
        # [Q₁ R] on one state space (plant, then filter)
        nq = Aq.shape[0]
        Bqy, Dqy = Bq0[:, mu:], Dq0[:, mu:]
        A = np.block([[model.A, np.zeros((n, nq))], [Bqy @ model.C, Aq]])
        Bq, Br = np.vstack([np.zeros((n, mu + p)), Bq0]), np.vstack([Bfw, Bqy @ Dfw])
        C, Dq, Dr = np.hstack([Dqy @ model.C, Cq]), Dq0, Dqy @ Dfw
    # rows of R scaled to comparable gains before the minimal realisation: PATH's rows span six decades, which
    # defeated its rank decisions (a state of the weak rows dropped) and those of the zero removal
    gains = np.max([np.linalg.norm(transfer((A, Br, C, Dr), z * basis.scale), axis=1) for z in _POINTS], axis=0)
    W = np.diag(1.0 / np.maximum(gains, 1e-300))
    A, B, C, D = minimal_realization(A, np.hstack([Bq, Br]), W @ C, W @ np.hstack([Dq, Dr]))
    return A, B[:, : mu + p], B[:, mu + p:], C, D[:, : mu + p], D[:, mu + p:]
