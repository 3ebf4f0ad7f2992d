"""Stabilisation of a nullspace filter whose internal form keeps unstable plant modes (Varga 2017, §5.2, §7.5).

The nullspace basis decouples the controls, disturbances and nuisance faults and gets stable denominators, but a
plant mode that only the fault or noise inputs excite (an integrator driven by a fault, ``G_f = [1/s  1/(s²+4)]``)
stays in ``R_f = Q [G_f; 0]`` and ``R_w``: the filter is stable, its internal form is not, and no H∞ measure of
it is finite.  The reference makes the joint ``[Q  R_f  R_w]`` stable by a left coprime factorisation (``glcf``
with ``sdeg``, ``smarg``, ``poles``) before the detectability checks and the noise factorisation.  For one residual
row that factorisation is ``M = a(λ) / φ(λ)``, ``a`` the polynomial of the row's poles outside the stability
margin and ``φ`` the assigned one, so :func:`stabilize_rows` applies it row by row (a diagonal ``M``, which is a
left coprime factor of the stacked rows as well); the unstable poles then cancel between ``M`` and the plant, and
the internal form's minimal realisation has only stable poles.

References
----------
Varga (2017), §5.2 (Procedure EFD, step 2: the stable filter), §7.5 (coprime factorisations); fdtools (``glcf``
in ``efdsyn``, ``afdsyn``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from fdikit.model import FaultModel
from fdikit.residuals import ResidualGenerator

__all__ = ["stabilize_rows"]


def _hidden_unstable_modes(model: FaultModel, nuisance: Sequence[str], smarg: float | None) -> np.ndarray:
    """Eigenvalues of ``A`` beyond the margin that ``[B_u B_d B_n]`` does not reach (PBH test): the basis, computed
    on the minimal realisation of ``[G_u G_d G_n]``, cannot remove them."""
    eps = np.sqrt(np.finfo(float).eps)
    ev = np.linalg.eigvals(model.A) if model.n else np.zeros(0)
    if model.dt is None:
        ev = ev[ev.real >= (-eps if smarg is None else float(smarg))]
    else:
        ev = ev[np.abs(ev) >= (1 - eps if smarg is None else float(smarg))]
    cols = [model.faults.index(f) for f in nuisance]
    Bdec = np.hstack([model.b("u"), model.b("d"), model.b("f")[:, cols]])
    scale = max(1.0, np.linalg.norm(np.hstack([model.A, Bdec]), 2))
    hidden = [lam for lam in ev
              if np.linalg.svd(np.hstack([model.A - lam * np.eye(model.n), Bdec]), compute_uv=False)[-1]
              <= 1e-9 * scale]
    return np.asarray(hidden, complex)


def stabilize_rows(gen: ResidualGenerator, model: FaultModel, *, nuisance: Sequence[str] = (),
                   poles: Sequence[complex] | None = None, sdeg: float | None = None,
                   smarg: float | None = None) -> tuple[ResidualGenerator, int]:
    """``M Q`` with ``M = diag(a_i/φ_i)`` moving the unstable poles of each row's ``[R_f R_w]`` to ``poles``/``sdeg``.

    Parameters
    ----------
    gen : ResidualGenerator
        A stable filter of ``model`` (a nullspace design before scaling).
    model : FaultModel
        The plant.
    nuisance : sequence of str, default ()
        The fault inputs the filter decouples (with the controls and disturbances): the plant modes beyond the
        margin that these inputs do not reach are the ones the nullspace leaves in the internal form, and only
        those (where a row's minimal ``[R_f R_w]`` has them) are moved — a mode the decoupled inputs reach is
        cancelled by the basis, and rounding would only make it look present.
    poles, sdeg : optional
        The assigned poles (first ``deg a_i`` of them) or stability degree (default −0.05, discrete 0.95), as the
        basis denominators (:func:`~fdikit.design.nullspace.basis.denominator`).
    smarg : float, optional
        Stability margin: poles with real part at least ``smarg`` (modulus at least ``smarg`` when discrete) are
        candidates; default ``−√ε`` (``1 − √ε``), the boundary and the unstable ones.

    Returns
    -------
    generator : ResidualGenerator
        ``gen`` itself when nothing is moved.
    moved : int
        The number of poles moved over all rows.

    Examples
    --------
    A fault through an integrator, ``G_f = 1/s``: the filter ``Q = 1`` leaves the pole 0 in ``R_f``; ``M = s/(s+1)``:

    >>> m = FaultModel([[0.0]], [[1.0]], Bf=[[1.0]], faults=["f"])
    >>> q = ResidualGenerator(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[1.0]], controls=(),
    ...                       outputs=m.outputs, residuals=("r",))
    >>> g, moved = stabilize_rows(q, m, sdeg=-1.0)
    >>> moved, np.round(np.linalg.eigvals(g.A).real, 6).tolist()
    (1, [-1.0])

    References
    ----------
    Varga (2017), §7.5; fdtools (``glcf``).
    """
    from fdikit.analysis.channels import minimal_channel
    from fdikit.design.nullspace.basis import denominator, minimal_realization
    from fdikit.design.nullspace.factorization import series
    from fdikit.design.nullspace.row_factors import realize_biproper

    inputs = list(model.faults) + list(model.noise)
    cand = _hidden_unstable_modes(model, nuisance, smarg)
    if not inputs or not cand.size:
        return gen, 0
    form = gen.internal_form(model)
    blocks, moved = [], 0
    for name in gen.residuals:
        ev = np.linalg.eigvals(minimal_channel(form, inputs, [name]).A)
        near = np.abs(ev[:, None] - cand[None, :]) <= 1e-6 * np.maximum(1.0, np.abs(cand))[None, :]
        bad = ev[near.any(axis=1)]
        moved += bad.size
        blocks.append(realize_biproper(np.real(np.poly(bad)), denominator(bad.size, poles, sdeg, model.dt)))
    if not moved:
        return gen, 0
    q = len(blocks)
    nb = [b[0].shape[0] for b in blocks]
    A = np.zeros((sum(nb), sum(nb)))
    B, C, D = np.zeros((sum(nb), q)), np.zeros((q, sum(nb))), np.zeros((q, q))
    k = 0
    for i, (Ab, Bb, Cb, Db) in enumerate(blocks):
        A[k:k + nb[i], k:k + nb[i]], B[k:k + nb[i], i], C[i, k:k + nb[i]], D[i, i] = Ab, Bb[:, 0], Cb[0], Db[0, 0]
        k += nb[i]
    A, B, C, D = minimal_realization(*series((gen.A, gen.B, gen.C, gen.D), (A, B, C, D)))
    return dataclasses.replace(gen, A=A, B=B, C=C, D=D), moved
