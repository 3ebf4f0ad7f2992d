"""Weak and strong structure matrices of internal forms (Varga's ``fditspec`` and ``fdisspec``).

The structure matrix ``S`` of the fault channel ``R_f`` of a filter says which residual (row) responds
to which fault (column), Varga (2017), §3.4:

* :func:`fditspec` — the **weak** structure matrix: ``S[i, j]`` True when the transfer function
  ``R_f,ij`` is not identically zero (decided on its minimal realisation: a nonzero ``D`` entry or a
  nonzero input vector, above ``tol``); with ``freqs`` the **strong** one by the rank of the system
  matrix ``[A − λI, b; c, d]`` of each element (no zero at any ``λ_k``);
* :func:`fdisspec` — the **strong** structure matrix at given frequencies by gains:
  ``S[i, j]`` True when ``|R_f,ij(λ_k)| > gain_tol`` at every ``λ_k`` (``λ = jω``, or ``e^{jω dt}``).

``block=True`` (and every bank: one row per filter) takes the column ``j`` of a filter as a whole
(its 2-norm / its being nonzero).  Rows are residuals (or filters), columns faults, as in the reference;
fdikit's :func:`~fdikit.analysis.structure_matrix` and :class:`~fdikit.decision.signature.SignatureTable`
write faults as rows: :meth:`StructureMatrix.to_pandas` gives that fault × group frame and
:meth:`StructureMatrix.signature_table` the isolation table.

Poles at a frequency of ``freqs`` are refused (the reference's default ``stabilize=false`` /
``poleshift=false``; the stabilising pre-filter ``M(λ)`` is not implemented).

References
----------
Varga (2017), §3.4 (structure matrices, Corollaries 7.1–7.2 for their computation); fdtools.

Examples
--------
>>> from fdikit import FaultModel
>>> R = FaultModel(A=[[-1.0]], C=[[1.0], [0.0]], Bf=[[1.0, 0.0]], Df=[[0.0, 0.0], [0.0, 2.0]],
...                faults=["f1", "f2"], outputs=["r1", "r2"])
>>> S = fdisspec(R)
>>> S.matrix.tolist(), S.rows, S.faults
([[True, False], [False, True]], ('r1', 'r2'), ('f1', 'f2'))
>>> S.signature_table().label({"r2"})
'f2'
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.analysis.channels import (
    check_freqs,
    frequency_response,
    internal_forms,
    minimal_channel,
)
from fdikit.errors import ModelError

__all__ = ["StructureMatrix", "fditspec", "fdisspec"]

_EPS = np.finfo(float).eps


@dataclass(frozen=True, eq=False)
class StructureMatrix:
    """A binary structure matrix of the fault channel, rows (residuals or filters) × faults.

    Attributes
    ----------
    matrix : (rows, faults) bool ndarray
        ``matrix[i, j]`` True when row ``i`` responds to fault ``j`` (Varga's ``S``).
    rows : tuple of str
        Residual names, or filter names for a bank / ``block=True``.
    faults : tuple of str
        Fault names.
    members : tuple of tuple of str
        The residuals of each row.
    kind : {'weak', 'strong'}
        Which structure matrix.
    freqs : ndarray or None
        The frequencies [rad/s] of a strong matrix.
    gains : (rows, faults, len(freqs)) ndarray or None
        :func:`fdisspec`'s gains ``|R_f,ij(λ_k)|`` (column 2-norms for blocks).

    Examples
    --------
    >>> S = StructureMatrix(np.array([[True, False]]), ("r",), ("f1", "f2"), (("r",),), "weak")
    >>> S.to_pandas()["r"].tolist()
    [True, False]
    """

    matrix: np.ndarray
    rows: tuple[str, ...]
    faults: tuple[str, ...]
    members: tuple[tuple[str, ...], ...]
    kind: str
    freqs: np.ndarray | None = None
    gains: np.ndarray | None = None

    def to_pandas(self):
        """The fault × group boolean DataFrame (index ``fault``, columns ``residual``), as ``structure_matrix``."""
        import pandas as pd

        return pd.DataFrame(self.matrix.T.copy(), index=pd.Index(self.faults, name="fault"),
                            columns=pd.Index(self.rows, name="residual"))

    def signature_table(self, match: str = "exact"):
        """The :class:`~fdikit.decision.signature.SignatureTable` of this matrix (groups = rows, with members)."""
        from fdikit.decision.signature import SignatureTable

        return SignatureTable(self.to_pandas(), members=dict(zip(self.rows, self.members)), match=match)


def _units(sysr, groups, block: bool):
    bank = internal_forms(sysr, groups)
    if bank.bank or block:
        return bank, [(nm, f, None) for nm, f in zip(bank.names, bank.forms)], list(bank.members)
    form = bank.forms[0]
    return bank, [(r, form, [r]) for r in form.outputs], [(r,) for r in form.outputs]


def _result(bank, units, members, S, kind, freqs=None, gains=None) -> StructureMatrix:
    S = np.asarray(S, dtype=bool).reshape(len(units), len(bank.faults))
    S.setflags(write=False)
    return StructureMatrix(S, tuple(u[0] for u in units), bank.faults, tuple(tuple(m) for m in members), kind,
                           freqs, gains)


def fdisspec(sysr, freqs=0.0, *, block: bool = False, gain_tol: float = 0.01, groups=None) -> StructureMatrix:
    """Strong structure matrix at ``freqs`` by frequency-response gains (``FDGainTol``).

    ``S[i, j]`` is True when ``|R_f,ij(λ_k)| > gain_tol`` for every frequency (``block=True`` and banks:
    the 2-norm of column ``j`` of the filter).  The gain of row ``i`` is evaluated on the minimal
    realisation of that row (hidden plant modes do not count as poles).

    Parameters
    ----------
    sysr : FaultModel, design result, or a bank (sequence / mapping of them)
        The internal form(s).
    freqs : float or array_like, default 0
        Frequencies [rad/s] of the persistent faults (0: constant faults; ``inf`` in continuous time: ``D``).
    block : bool, default False
        One row for the whole filter (column norms).
    gain_tol : float, default 0.01
        Absolute gain threshold (the reference's ``FDGainTol``).
    groups : mapping or sequence, optional
        With one internal form: the residuals of each filter of a stacked bank (one row each).

    Returns
    -------
    StructureMatrix
        ``kind='strong'``, with ``freqs`` and ``gains``.

    Raises
    ------
    ModelError
        When a frequency is a pole of a row's (or filter's) fault channel, or the form has no faults.
    ParameterError
        For bad ``freqs``, ``gain_tol`` or ``groups``.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[1.0, 0.005]], faults=["f1", "f2"], outputs=["r"])
    >>> S = fdisspec(R, [0.0, 1.0])
    >>> S.matrix.tolist(), np.round(S.gains[0, 0], 6).tolist()
    ([[True, False]], [1.0, 0.707107])
    """
    gain_tol = validate.non_negative("gain_tol", gain_tol)
    bank, units, members = _units(sysr, groups, block)
    if not bank.faults:
        raise ModelError("the internal form has no faults (group f); no structure matrix")
    omega = check_freqs(freqs, bank.dt)
    gains = np.empty((len(units), len(bank.faults), omega.size))
    for i, (_, form, outputs) in enumerate(units):
        H = frequency_response(minimal_channel(form, list(bank.faults), outputs), omega)  # (N, p, m)
        gains[i] = np.linalg.norm(H, axis=1).T
    return _result(bank, units, members, np.all(gains > gain_tol, axis=2), "strong", omega, gains)


def fditspec(sysr, freqs=None, *, block: bool = False, tol: float | None = None, stol: float | None = None,
             groups=None) -> StructureMatrix:
    """Weak structure matrix (nonzero transfer functions), or strong at ``freqs`` (no zero there).

    Weak: ``S[i, j]`` True when the minimal realisation of ``R_f,ij`` (``block=True`` / banks: of column
    ``j`` of the filter) has ``|d| > tol`` or an input vector entry ``> tol``; ``tol`` (``FDtol``) defaults
    to ``1e-4 max(1, ‖B_f‖₁, ‖D_f‖₁)`` of the filter's fault channel.  Strong (``freqs`` given): True when
    the system matrix ``[A − λ_k I, b; c, d]`` of that minimal realisation has full column rank at every
    ``λ_k``, i.e. its smallest singular value exceeds ``stol`` (``FDStol``, default
    ``100 (n + 1) ε max(1, ‖A‖₁, ‖B‖₁, ‖C‖∞, ‖D‖₁)``, ``n`` the element's order).  The reference's default
    ``ε max(…)`` sits at the rounding level of the element's minimal realisation, so a zero exactly at ``λ_k``
    could be missed: ``s/(s + 1)`` of test_efdsyn.jl's ``G_f = [s/(s+1) 0; (s²+4)/(s+3)² 1]``, realised and
    reduced, gave ``σ_min = 2e-15`` at ``λ = 0`` against ``ε max(…) = 3.3e-16`` (True instead of the reference's
    False); the factor ``100 (n + 1)`` is the usual margin of a backward-stable reduction and SVD of an
    ``(n + 1)``-dimensional pencil.

    Parameters
    ----------
    sysr : FaultModel, design result, or a bank (sequence / mapping of them)
        The internal form(s).
    freqs : float or array_like, optional
        Frequencies [rad/s] for the strong matrix; default the weak one.
    block : bool, default False
        One row for the whole filter.
    tol, stol : float, optional
        The weak and strong thresholds above.
    groups : mapping or sequence, optional
        With one internal form: the residuals of each filter of a stacked bank (one row each).

    Returns
    -------
    StructureMatrix
        ``kind='weak'`` or ``'strong'``.

    Raises
    ------
    ModelError
        When a frequency is a pole of an element's minimal realisation, or the form has no faults.
    ParameterError
        For bad ``freqs``, tolerances or ``groups``.

    Examples
    --------
    >>> from fdikit import FaultModel
    >>> R = FaultModel(A=[[-1.0]], C=[[1.0]], Bf=[[-1.0, 0.0]], Df=[[1.0, 0.0]], faults=["f1", "f2"])
    >>> fditspec(R).matrix.tolist()   # s/(s + 1) and 0
    [[True, False]]
    >>> fditspec(R, [0.0]).matrix.tolist(), fditspec(R, [1.0]).matrix.tolist()   # its zero at s = 0
    ([[False, False]], [[True, False]])
    """
    tol = None if tol is None else validate.non_negative("tol", tol)
    stol = None if stol is None else validate.non_negative("stol", stol)
    bank, units, members = _units(sysr, groups, block)
    if not bank.faults:
        raise ModelError("the internal form has no faults (group f); no structure matrix")
    omega = None if freqs is None else check_freqs(freqs, bank.dt)
    S = np.zeros((len(units), len(bank.faults)), dtype=bool)
    for i, (_, form, outputs) in enumerate(units):
        Bf, Df = form.Bf, form.Df if outputs is None else form.submodel(outputs=outputs).Df
        t1 = tol if tol is not None else 1e-4 * max(1.0, np.linalg.norm(Bf, 1), np.linalg.norm(Df, 1))
        for j, f in enumerate(bank.faults):
            ch = minimal_channel(form, [f], outputs)
            if omega is None:
                S[i, j] = bool(np.any(np.abs(ch.D) > t1) or (ch.n > 0 and np.any(np.abs(ch.B) > t1)))
                continue
            S[i, j] = _no_zero(ch, omega, stol, f)
    return _result(bank, units, members, S, "weak" if omega is None else "strong", omega)


def _no_zero(ch, omega: np.ndarray, stol: float | None, fault: str) -> bool:
    n = ch.n
    scale = max(1.0, np.linalg.norm(ch.D, 1), *(
        (np.linalg.norm(ch.A, 1), np.linalg.norm(ch.B, 1), np.linalg.norm(ch.C, np.inf)) if n else ()))
    t2 = 100 * (n + 1) * _EPS * scale if stol is None else stol
    for w in omega:
        if n and not np.isinf(w):
            lam = np.exp(1j * w * ch.dt) if ch.dt is not None else 1j * w
            if np.linalg.svd(lam * np.eye(n) - ch.A, compute_uv=False)[-1] <= n * _EPS * scale:
                raise ModelError(f"the frequency {w:g} rad/s is a pole of the channel of fault {fault!r}; the strong "
                                 "structure is defined where R_f has no poles (stabilise or pick other freqs)")
            P = np.block([[ch.A - lam * np.eye(n), ch.B], [ch.C, ch.D]])
        else:
            P = ch.D.astype(complex)  # n = 0, or λ = ∞: the D term decides
        if np.linalg.svd(P, compute_uv=False)[-1] <= t2:  # a zero of the element (column) at λ
            return False
    return True
