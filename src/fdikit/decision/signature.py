"""Isolation from a fault-signature (structure) table: the fault whose pattern of residual groups fired.

A fault signature table (a *structure matrix*) says, for every fault, which residual groups respond
to it: ``S[f, g]`` True when group ``g`` fires under fault ``f``.  Per sample, the set ``F`` of
fired groups (a group fires when any of its residuals fires) is matched against the rows:

* ``match='exact'`` (default): the fault is named when ``F`` equals its signature and no other
  fault has that signature; a fault that fires several groups is thus named once its *whole*
  pattern fired (a rudder runaway seen by two observer groups), not ``'unknown'`` as under the
  single-residual rule of :func:`fdikit.diagnosis.isolate`;
* ``match='partial'``: as ``'exact'``, and a pattern that equals no signature is also named when it
  is part of the signature of exactly one fault (``F ⊂ S_f`` for one ``f`` only) — a multi-group
  fault is named as soon as the part of its pattern that fired rules out every other fault;
* everything else — a pattern no fault produces, a pattern shared by two or more faults
  (indistinguishable signatures: :attr:`SignatureTable.indistinguishable`) — is ``'unknown'``;
  no fired group is ``'none'``.

The table is given as a mapping fault → fired groups, a boolean DataFrame (rows faults, columns
groups) or, from a design, by :meth:`SignatureTable.from_generator`
(:func:`fdikit.analysis.structure_matrix`).  Residuals belong to the groups of
:meth:`SignatureTable.resolve`.  Evaluators that decide per residual take it as ``signatures=``
(:class:`~fdikit.decision.ThresholdEvaluator`, :class:`~fdikit.decision.CusumEvaluator`,
:class:`~fdikit.decision.GlrEvaluator`, :class:`~fdikit.decision.SprtEvaluator`); ``run`` and
``step`` name the same fault for the same fired pattern.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT

__all__ = ["MATCH_RULES", "SignatureTable", "as_signature_table", "signature_isolation"]

#: The ``match=`` rules of :class:`SignatureTable`.
MATCH_RULES = ("exact", "partial")

_UNKNOWN = "unknown"  # fdikit.diagnosis.UNKNOWN_FAULT (not imported: keeps this module free of a cycle)


class SignatureTable:
    """Fault × residual-group signatures and the isolation logic that matches fired patterns to them.

    Parameters
    ----------
    table : mapping or pandas.DataFrame
        ``{fault: fired groups}`` (an iterable of group names; an empty one is an undetectable fault),
        or a boolean DataFrame with one row per fault and one column per residual group (as
        :func:`fdikit.analysis.structure_matrix` returns).
    members : mapping, optional
        ``{group: residual names}``: the residuals of each group.  Without it a group is resolved from
        the residuals' names and tied faults (:meth:`resolve`).
    match : {'exact', 'partial'}, default 'exact'
        The matching rule (module docstring).

    Attributes
    ----------
    faults : tuple of str
        The faults (rows).
    groups : tuple of str
        The residual groups (columns).
    matrix : (n_faults, n_groups) bool ndarray
        The signatures.
    indistinguishable : tuple of tuple of str
        Sets of two or more detectable faults with the same signature: never named, always ``'unknown'``.
    undetectable : tuple of str
        Faults that fire no group.

    Raises
    ------
    ParameterError
        When the table is empty or not boolean, a fault has two rows, a mapping names a group twice,
        ``members`` names a group not in the table, or ``match`` is unknown.

    References
    ----------
    Douglas et al. 1996, §1 (each residual tied to a fault; the fault is announced from the pattern of residuals
    that cross their thresholds, and no announcement when the pattern points to no single fault) and §4.1
    (the structure of fault-to-residual gains of a detection filter bank).

    Examples
    --------
    >>> from fdikit.decision.signature import SignatureTable
    >>> tab = SignatureTable({"rudder_actuator": ["yaw", "roll"], "aileron_actuator": ["roll"],
    ...                       "yaw_rate_sensor": ["yaw"]})
    >>> tab.label({"yaw", "roll"}), tab.label({"roll"}), tab.label(set()), tab.label({"pitch"})
    ('rudder_actuator', 'aileron_actuator', 'none', 'unknown')
    >>> SignatureTable({"a": ["g1"], "b": ["g1"], "c": ["g2"]}).indistinguishable
    (('a', 'b'),)
    """

    def __init__(self, table, members: Mapping[str, Sequence[str]] | None = None, match: str = "exact") -> None:
        if match not in MATCH_RULES:
            raise ParameterError(f"match must be one of {list(MATCH_RULES)}, got {match!r}")
        self.match = match
        if isinstance(table, SignatureTable):
            faults, groups, matrix = table.faults, table.groups, table.matrix
            members = table.members if members is None else members
        elif isinstance(table, Mapping):
            faults = tuple(str(f) for f in table)
            groups_l: list[str] = []
            for f, gs in table.items():
                if isinstance(gs, str):
                    gs = (gs,)
                gs = [str(g) for g in gs]
                if len(set(gs)) != len(gs):
                    raise ParameterError(f"fault {f!r} lists a residual group twice: {gs}")
                groups_l += [g for g in gs if g not in groups_l]
            groups = tuple(groups_l)
            matrix = np.array([[g in {str(x) for x in ((gs,) if isinstance(gs, str) else gs)} for g in groups]
                               for gs in table.values()], dtype=bool).reshape(len(faults), len(groups))
        elif hasattr(table, "to_numpy") and hasattr(table, "columns") and hasattr(table, "index"):
            raw = np.asarray(table.to_numpy())
            if raw.dtype != bool:
                raise ParameterError(
                    f"a signature DataFrame must be boolean (True where a group fires), got {raw.dtype}"
                )
            faults = tuple(str(f) for f in table.index)
            groups = tuple(str(g) for g in table.columns)
            matrix = raw.reshape(len(faults), len(groups))
        else:
            raise ParameterError(
                "signatures must be a SignatureTable, a mapping {fault: fired groups} or a boolean DataFrame "
                f"(faults × groups, e.g. fdikit.analysis.structure_matrix), got {type(table).__name__}"
            )
        if not faults:
            raise ParameterError("the signature table has no faults; give at least one fault and its groups")
        if len(set(faults)) != len(faults):
            raise ParameterError(f"a fault appears twice in the signature table: {list(faults)}")
        if len(set(groups)) != len(groups):
            raise ParameterError(f"a residual group appears twice in the signature table: {list(groups)}")
        self.faults, self.groups = tuple(faults), tuple(groups)
        self.matrix = np.array(matrix, dtype=bool)
        self.matrix.setflags(write=False)
        if members is not None:
            members = {str(g): (m,) if isinstance(m, str) else tuple(str(x) for x in m) for g, m in members.items()}
            extra = [g for g in members if g not in self.groups]
            if extra:
                raise ParameterError(f"members name group(s) {extra} that are not in the table {list(self.groups)}")
        self.members = members
        self._rows = {f: frozenset(g for g, s in zip(self.groups, row) if s)
                      for f, row in zip(self.faults, self.matrix)}

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_generator(cls, generator, model, *, match: str = "exact", **structure_options) -> SignatureTable:
        """The table of a design: :func:`fdikit.analysis.structure_matrix` of ``generator`` on ``model``.

        Parameters
        ----------
        generator : ResidualGenerator
            The residual generator (a design's ``.generator``).
        model : FaultModel
            The model it runs on.
        match : {'exact', 'partial'}, default 'exact'
            The matching rule.
        **structure_options
            ``freqs``, ``rtol``, ``faults``, ``atol`` of :func:`~fdikit.analysis.structure_matrix`.

        Returns
        -------
        SignatureTable
            Its groups are the generator's residual groups, with their residuals as ``members``.

        Raises
        ------
        ParameterError
            For the arguments :func:`~fdikit.analysis.structure_matrix` refuses.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit import FaultModel
        >>> from fdikit.design import observer_generator
        >>> m = FaultModel(A=np.diag([-1.0, -2.0]), C=np.eye(2), Bu=np.array([[1.0, 0.0], [1.0, 1.0]]),
        ...                outputs=["y0", "y1"], controls=["u0", "u1"]).with_actuator_faults(["u0", "u1"])
        >>> gen = observer_generator(m, np.diag([4.0, 5.0]), isolates=["u0_actuator", "u1_actuator"])
        >>> tab = SignatureTable.from_generator(gen, m)
        >>> tab.signature("u0_actuator"), tab.signature("u1_actuator")
        (('u0_actuator', 'u1_actuator'), ('u1_actuator',))
        """
        from fdikit.analysis import fault_to_residual_gain, structure_matrix
        from fdikit.analysis.gains import default_freqs

        S = structure_matrix(generator, model, **structure_options)
        dt = generator.dt if generator.dt is not None else model.dt
        one = default_freqs(dt)[:1]
        gains = fault_to_residual_gain(generator, model, one, structure_options.get("faults"))
        members = dict(zip(gains.groups, gains.members))
        return cls(S, members=members, match=match)

    # ------------------------------------------------------------------ reports
    def signature(self, fault: str) -> tuple[str, ...]:
        """The groups ``fault`` fires, in table order (:class:`~fdikit.errors.ParameterError` for an unknown fault)."""
        if fault not in self._rows:
            raise ParameterError(f"fault {fault!r} is not in the signature table {list(self.faults)}")
        return tuple(g for g in self.groups if g in self._rows[fault])

    @property
    def indistinguishable(self) -> tuple[tuple[str, ...], ...]:
        by: dict[frozenset, list[str]] = {}
        for f, s in self._rows.items():
            if s:
                by.setdefault(s, []).append(f)
        return tuple(tuple(v) for v in by.values() if len(v) > 1)

    @property
    def undetectable(self) -> tuple[str, ...]:
        return tuple(f for f, s in self._rows.items() if not s)

    @property
    def isolable(self) -> tuple[str, ...]:
        """Faults named when exactly their signature fires (detectable, signature shared with no other fault)."""
        shared = {f for fs in self.indistinguishable for f in fs}
        return tuple(f for f, s in self._rows.items() if s and f not in shared)

    def to_pandas(self):
        """The table as a boolean DataFrame (index ``fault``, columns ``residual``)."""
        import pandas as pd

        return pd.DataFrame(self.matrix, index=pd.Index(self.faults, name="fault"),
                            columns=pd.Index(self.groups, name="residual"))

    # ------------------------------------------------------------------ logic
    def label(self, fired_groups) -> str:
        """The fault named for a set of fired groups: a fault name, ``'unknown'`` or ``'none'`` (module docstring).

        Groups not in the table make the pattern ``'unknown'``.
        """
        F = frozenset(str(g) for g in fired_groups)
        if not F:
            return NO_FAULT
        exact = [f for f, s in self._rows.items() if s == F]
        if len(exact) == 1:
            return exact[0]
        if exact:  # indistinguishable signatures
            return _UNKNOWN
        if self.match == "partial":
            part = [f for f, s in self._rows.items() if F < s]
            if len(part) == 1:
                return part[0]
        return _UNKNOWN

    def resolve(self, names: Sequence[str], isolates: Sequence[str | None] | None = None) -> np.ndarray:
        """Membership of residuals in the table's groups: a (q, n_groups) bool matrix.

        Residual ``i`` belongs to group ``g`` when ``g`` is its name, its tied fault ``isolates[i]``, or,
        for a stacked bank residual named ``'<filter>:<...>'``, ``'<filter>:<isolates[i]>'`` (the groups of
        :func:`fdikit.analysis.structure_matrix`) — except that a residual listed in ``members`` belongs
        exactly to the groups that list it.  (The GLR and SPRT fire per *block*: a block named after its
        fault, as with ``blocks='isolates'``, finds its group by that rule.)

        Parameters
        ----------
        names : sequence of str
            Residual names.
        isolates : sequence of str or None, optional
            The fault tied to each residual.

        Returns
        -------
        (q, n_groups) bool ndarray
            ``M[i, g]`` True when residual ``i`` is in group ``g``.

        Raises
        ------
        DataError
            When a residual is in no group, or a group has no residual (give ``members=``).
        """
        names = tuple(names)
        iso = tuple(isolates) if isolates is not None else (None,) * len(names)
        if len(iso) != len(names):
            raise DataError(f"{len(iso)} 'isolates' entries for {len(names)} residuals")
        M = np.zeros((len(names), len(self.groups)), bool)
        for j, g in enumerate(self.groups):
            for i, (n, f) in enumerate(zip(names, iso)):
                M[i, j] = g == n or (f is not None and (g == f or (":" in n and g == f"{n.split(':', 1)[0]}:{f}")))
        if self.members is not None:
            listed = np.array([[n in self.members.get(g, ()) for g in self.groups] for n in names], bool)
            listed = listed.reshape(M.shape)
            M = np.where(listed.any(axis=1, keepdims=True), listed, M)
        lonely = [n for n, row in zip(names, M) if not row.any()]
        if lonely:
            raise DataError(
                f"residual(s) {lonely} belong to no group of the signature table {list(self.groups)}; give "
                "members={group: [residual names]} or a table whose columns are the residual names or their faults"
            )
        empty = [g for g, col in zip(self.groups, M.T) if not col.any()]
        if empty:
            raise DataError(
                f"group(s) {empty} of the signature table contain none of the residuals {list(names)}; "
                "give members={group: [residual names]}"
            )
        return M

    def isolate(self, fired, names: Sequence[str], isolates: Sequence[str | None] | None = None) -> np.ndarray:
        """Per-sample isolated fault from per-residual decisions (:func:`signature_isolation`)."""
        return signature_isolation(fired, self, names, isolates)

    def __repr__(self) -> str:
        return f"SignatureTable(faults={list(self.faults)}, groups={list(self.groups)}, match={self.match!r})"


def as_signature_table(signatures) -> SignatureTable | None:
    """``signatures`` as a :class:`SignatureTable` (None stays None): a table, a mapping or a boolean DataFrame.

    Parameters
    ----------
    signatures : SignatureTable, StructureMatrix, mapping, pandas.DataFrame or None
        The fault signatures (a :class:`~fdikit.analysis.structure.StructureMatrix` gives its
        :meth:`~fdikit.analysis.structure.StructureMatrix.signature_table`).

    Returns
    -------
    SignatureTable or None
        The table.

    Raises
    ------
    ParameterError
        For a value :class:`SignatureTable` refuses.

    References
    ----------
    Douglas et al. 1996, §1 (see :class:`SignatureTable`).

    Examples
    --------
    >>> from fdikit.decision.signature import as_signature_table
    >>> as_signature_table({"fa": ["ra"]}).faults, as_signature_table(None)
    (('fa',), None)
    """
    if signatures is None or isinstance(signatures, SignatureTable):
        return signatures
    if hasattr(signatures, "signature_table"):  # a StructureMatrix (fdikit.analysis.structure): rows are the groups
        return signatures.signature_table()
    return SignatureTable(signatures)


def signature_isolation(fired, table, names: Sequence[str], isolates: Sequence[str | None] | None = None,
                        membership: np.ndarray | None = None) -> np.ndarray:
    """Per-sample isolated fault: the fired residuals' groups matched against the signature table.

    Parameters
    ----------
    fired : (N, q) or (q,) bool array_like
        Per-sample, per-residual decisions.
    table : SignatureTable or mapping or pandas.DataFrame
        The fault signatures (:class:`SignatureTable`).
    names : sequence of str
        Residual names (columns of ``fired``).
    isolates : sequence of str or None, optional
        The fault tied to each residual (for :meth:`SignatureTable.resolve`).
    membership : (q, n_groups) bool ndarray, optional
        A precomputed :meth:`SignatureTable.resolve`.

    Returns
    -------
    (N,) str ndarray
        ``'none'``, a fault name or ``'unknown'`` per sample (a 1-D ``fired`` gives one label).

    Raises
    ------
    DataError
        When the residuals do not map onto the table's groups, or ``fired`` has not ``len(names)`` columns.

    References
    ----------
    Douglas et al. 1996, §1 (see :class:`SignatureTable`).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.signature import signature_isolation
    >>> fired = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=bool)
    >>> signature_isolation(fired, {"fa": ["ra", "rb"], "fb": ["rb"]}, ("ra", "rb")).tolist()
    ['none', 'unknown', 'fa', 'fb']
    """
    table = as_signature_table(table)
    f = np.asarray(fired, bool)
    one = f.ndim == 1
    f = np.atleast_2d(f)
    if f.shape[1] != len(names):
        raise DataError(f"fired has {f.shape[1]} columns for {len(names)} residual names")
    M = table.resolve(names, isolates) if membership is None else membership
    if f.shape[0] == 0:
        return np.empty(0, dtype=str)
    G = (f.astype(np.int64) @ M.astype(np.int64)) > 0  # group fires when any of its residuals fires
    pats, inv = np.unique(G, axis=0, return_inverse=True)
    labels = np.array([table.label(g for g, on in zip(table.groups, p) if on) for p in pats], dtype=object)
    out = labels[np.asarray(inv).ravel()].astype(str)
    return out[:1] if one else out
