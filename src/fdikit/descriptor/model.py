"""Descriptor state-space models with grouped inputs: ``E x' = A x + B u``, ``y = C x + D u``.

A :class:`DescriptorModel` is the descriptor form of :class:`fdikit.model.FaultModel` (Varga's ``fdimodset`` on a
descriptor plant)::

    E x' = A x + Bu u + Bd d + Bf f + Bw w + Baux aux        (x' = dx/dt, or x[k+1])
       y = C x + Du u + Dd d + Df f + Dw w + Daux aux

with ``E`` square and possibly singular (differential-algebraic equations, improper plants) and the pencil
``A − λE`` regular (``det(λE − A) ≢ 0``).  The groups are those of ``FaultModel`` plus ``aux``, the auxiliary
inputs of the reference toolbox (inputs carried along, e.g. for model detection; Varga 2017, §2.2.1).
Its transfer matrix is ``G(λ) = C (λE − A)⁻¹ B + D`` (:meth:`DescriptorModel.evaluate`), possibly improper.

Conversion: :meth:`DescriptorModel.from_fault_model` (``E = I``) and :meth:`DescriptorModel.to_fault_model`
(``E`` invertible: ``E⁻¹``; ``E`` singular: the non-dynamic modes — index-1 algebraic variables — are eliminated
and the feedthrough updated, then uncontrollable or unobservable infinite eigenvalues removed; what is left
singular is a polynomial (improper) part that a ``FaultModel`` cannot hold → :class:`ModelError`).

References
----------
Varga (2017), §2.2.1 (the model ``fdimodset`` sets up), §9.1.3 (descriptor systems, regular pencils, proper
and improper transfer matrices).  ``fdtools`` (FaultDetectionTools.jl: ``fdimodset`` on ``dss`` models).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from fdikit import validate
from fdikit.descriptor.staircase import pencil_structure
from fdikit.errors import ModelError, ParameterError
from fdikit.model import FaultModel

__all__ = ["DescriptorModel", "DESCRIPTOR_GROUPS"]

#: Input groups in the order their columns appear in ``B`` and ``D``.
DESCRIPTOR_GROUPS: tuple[str, ...] = ("u", "d", "f", "w", "aux")
_WORD = {"u": "controls", "d": "disturbances", "f": "faults", "w": "noise", "aux": "aux"}
_PREFIX = {"u": "u", "d": "d", "f": "f", "w": "w", "aux": "aux"}


def _block(name: str, value, rows: int, cols: int | None) -> np.ndarray:
    if value is None:
        out = np.zeros((rows, cols or 0))
    else:
        out = validate.as_array(name, value, error=ModelError)
        if out.ndim == 1 and cols == 1:
            out = out.reshape(-1, 1)
        if out.size == 0:
            out = np.zeros((rows, cols or 0))
        out = validate.as_matrix(name, out, (rows, cols), error=ModelError)
    out = np.array(out, dtype=float)
    out.setflags(write=False)
    return out


def _names(kind: str, names, count: int, prefix: str) -> tuple[str, ...]:
    if names is None:
        return tuple(f"{prefix}{i}" for i in range(count))
    if isinstance(names, str):
        raise ModelError(f"{kind} names must be a sequence of strings, got the single string {names!r}")
    names = tuple(names)
    bad = [n for n in names if not isinstance(n, str) or not n.strip()]
    if bad:
        raise ModelError(f"{kind} names must be non-empty strings, got {bad[0]!r}")
    if len(names) != count:
        raise ModelError(f"{len(names)} {kind} names given for {count} {kind}")
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise ModelError(f"duplicate {kind} name {dup!r}; names must be unique")
    return names


@dataclass(frozen=True, eq=False)
class DescriptorModel:
    """Continuous (``dt is None``) or discrete (``dt > 0``) descriptor model with grouped inputs.

    Parameters
    ----------
    A, C : array_like
        State and output matrices (n x n, p x n).
    E : array_like, optional
        Descriptor matrix (n x n), possibly singular; default the identity.
    Bu, Du, Bd, Dd, Bf, Df, Bw, Dw, Baux, Daux : array_like, optional
        Input and feedthrough blocks of the control, disturbance, fault, noise and auxiliary groups; a missing
        block is zero with as many columns as the group has names.
    states, outputs, controls, disturbances, faults, noise, aux : sequence of str, optional
        Names; default ``x0, ...``, ``y0, ...``, ``u0, ...``, ``d0, ...``, ``f0, ...``, ``w0, ...``, ``aux0, ...``.
    dt : float, optional
        Sample time of a discrete model (``E x[k+1] = A x[k] + ...``); ``None`` for continuous time.
    tol : float, optional
        Relative rank tolerance of the regularity test (:func:`fdikit.descriptor.staircase.pencil_structure`).

    Attributes
    ----------
    E, A, B, C, D : numpy.ndarray
        The matrices (read-only); ``B`` and ``D`` hold the groups side by side in the order u, d, f, w, aux.
    states, outputs : tuple of str
        Names.
    inputs : dict
        Group → input names.
    dt : float or None
        Sample time.

    Raises
    ------
    ModelError
        On a shape mismatch, a non-finite entry, a duplicate name, or a singular pencil (``det(λE − A) ≡ 0``:
        the equations do not determine ``x``).

    Examples
    --------
    >>> m = DescriptorModel(A=[[-1.0, 0.0], [1.0, -1.0]], E=[[1.0, 0.0], [0.0, 0.0]], C=[[0.0, 1.0]],
    ...                     Bu=[[1.0], [0.0]], controls=["v"], outputs=["i"])
    >>> m
    DescriptorModel(continuous, n=2, p=1, u=1, d=0, f=0, w=0, aux=0)
    >>> complex(m.evaluate(0.0)[0, 0]).real  # G(s) = 1/(s + 1) at s = 0
    1.0
    """

    E: np.ndarray
    A: np.ndarray
    B: np.ndarray = field(repr=False)
    C: np.ndarray
    D: np.ndarray = field(repr=False)
    states: tuple[str, ...]
    outputs: tuple[str, ...]
    inputs: dict[str, tuple[str, ...]]
    dt: float | None = None

    def __init__(self, A, C, *, E=None, Bu=None, Du=None, Bd=None, Dd=None, Bf=None, Df=None, Bw=None, Dw=None,
                 Baux=None, Daux=None, states: Sequence[str] | None = None, outputs: Sequence[str] | None = None,
                 controls: Sequence[str] | None = None, disturbances: Sequence[str] | None = None,
                 faults: Sequence[str] | None = None, noise: Sequence[str] | None = None,
                 aux: Sequence[str] | None = None, dt: float | None = None, tol: float | None = None) -> None:
        A = validate.as_matrix("A", A, error=ModelError)
        n = A.shape[0]
        if A.shape != (n, n):
            raise ModelError(f"A must be square, got shape {A.shape}")
        E = np.eye(n) if E is None else validate.as_matrix("E", E, (n, n), error=ModelError)
        C = _block("C", C, 0 if n == 0 and np.size(C) == 0 else np.atleast_2d(C).shape[0], n)
        p = C.shape[0]
        given = {"u": (Bu, Du, controls), "d": (Bd, Dd, disturbances), "f": (Bf, Df, faults),
                 "w": (Bw, Dw, noise), "aux": (Baux, Daux, aux)}
        bs, ds, groups = [], [], {}
        for g in DESCRIPTOR_GROUPS:
            Bg, Dg, names = given[g]
            if Bg is not None and np.size(Bg):
                count = _block(f"B{g}", Bg, n, None).shape[1]
            elif Dg is not None and np.size(Dg):
                count = _block(f"D{g}", Dg, p, None).shape[1]
            else:
                count = 0 if names is None else len(tuple(names))
            bs.append(_block(f"B{g}", Bg, n, count))
            ds.append(_block(f"D{g}", Dg, p, count))
            groups[g] = _names(_WORD[g], names, count, _PREFIX[g])
        every = [nm for g in DESCRIPTOR_GROUPS for nm in groups[g]]
        if len(set(every)) != len(every):
            dup = next(x for x in every if every.count(x) > 1)
            raise ModelError(f"input name {dup!r} is used in two groups; input names must be unique")
        if dt is not None:
            dt = validate.number("dt (the sample time)", dt, error=ModelError)
            if dt <= 0:
                raise ModelError(f"dt must be a positive sample time or None (continuous), got {dt}")
        if n:
            structure = pencil_structure(A, E, tol=tol)
            if not structure.is_regular:
                raise ModelError(
                    f"the pencil A − λE is singular (det(λE − A) ≡ 0; normal rank {structure.normal_rank} < n = {n}, "
                    f"right Kronecker indices {list(structure.right_indices)}): the equations do not determine the "
                    "state; remove the redundant equations or fix the free variables")
        for M in (A, E):
            M.setflags(write=False)
        B = np.hstack(bs)
        D = np.hstack(ds)
        B.setflags(write=False)
        D.setflags(write=False)
        for key, value in (("E", E), ("A", A), ("B", B), ("C", C), ("D", D), ("inputs", groups), ("dt", dt),
                           ("states", _names("state", states, n, "x")),
                           ("outputs", _names("output", outputs, p, "y"))):
            object.__setattr__(self, key, value)

    # ------------------------------------------------------------------ sizes and blocks
    @property
    def n(self) -> int:
        """Number of descriptor states."""
        return self.A.shape[0]

    @property
    def p(self) -> int:
        """Number of outputs."""
        return self.C.shape[0]

    @property
    def is_discrete(self) -> bool:
        """Whether the model is discrete."""
        return self.dt is not None

    controls = property(lambda self: self.inputs["u"], doc="Control input names (group ``u``).")
    disturbances = property(lambda self: self.inputs["d"], doc="Disturbance input names (group ``d``).")
    faults = property(lambda self: self.inputs["f"], doc="Fault input names (group ``f``).")
    noise = property(lambda self: self.inputs["w"], doc="Noise input names (group ``w``).")
    aux = property(lambda self: self.inputs["aux"], doc="Auxiliary input names (group ``aux``).")

    def _slice(self, group: str) -> slice:
        if group not in DESCRIPTOR_GROUPS:
            raise ParameterError(f"unknown input group {group!r}; use one of {DESCRIPTOR_GROUPS}")
        start = sum(len(self.inputs[g]) for g in DESCRIPTOR_GROUPS[: DESCRIPTOR_GROUPS.index(group)])
        return slice(start, start + len(self.inputs[group]))

    def b(self, group: str) -> np.ndarray:
        """Input matrix of one group (``'u'``, ``'d'``, ``'f'``, ``'w'`` or ``'aux'``)."""
        return self.B[:, self._slice(group)]

    def d(self, group: str) -> np.ndarray:
        """Feedthrough matrix of one group."""
        return self.D[:, self._slice(group)]

    def with_matrices(self, E, A, B, C, D, states: Sequence[str] | None = None) -> DescriptorModel:
        """A model with the same inputs, outputs and sample time and new matrices (``B``, ``D``: all groups).

        Parameters
        ----------
        E, A, B, C, D : array_like
            The new matrices; the number of states may change.
        states : sequence of str, optional
            State names; default ``x0, x1, ...``.

        Returns
        -------
        DescriptorModel
            The new model (checked as the constructor checks).

        Examples
        --------
        >>> m = DescriptorModel([[-1.0]], [[1.0]], Bu=[[1.0]])
        >>> m.with_matrices(2 * m.E, 2 * m.A, 2 * m.B, m.C, m.D).n
        1
        """
        B = np.asarray(B, dtype=float).reshape(np.shape(A)[0], self.B.shape[1])
        D = np.asarray(D, dtype=float).reshape(self.p, self.D.shape[1])
        kw = {"E": E, "A": A, "C": np.asarray(C, dtype=float).reshape(self.p, np.shape(A)[0]), "dt": self.dt,
              "states": states, "outputs": self.outputs}
        for g in DESCRIPTOR_GROUPS:
            sl = self._slice(g)
            kw[f"B{g}"], kw[f"D{g}"], kw[_WORD[g]] = B[:, sl], D[:, sl], self.inputs[g]
        return DescriptorModel(**kw)

    # ------------------------------------------------------------------ responses and poles
    def evaluate(self, lam, group: str | None = None) -> np.ndarray:
        """The transfer matrix ``G(λ) = C (λE − A)⁻¹ B + D`` at one point or an array of points.

        Parameters
        ----------
        lam : complex or array_like
            The point(s) ``λ`` (``s`` in continuous time, ``z`` in discrete time).
        group : str, optional
            One input group; default all inputs.

        Returns
        -------
        numpy.ndarray
            ``(p, k)`` complex for a scalar ``λ``, ``(len(λ), p, k)`` for an array.

        Raises
        ------
        ModelError
            If ``λ`` is a pole (``λE − A`` singular to working precision).

        Examples
        --------
        >>> m = DescriptorModel([[1.0]], [[1.0]], E=[[0.0]], Bu=[[1.0]])  # 0 = x + u: G = −1, no dynamics
        >>> complex(m.evaluate(5.0)[0, 0]).real
        -1.0
        """
        B, D = (self.B, self.D) if group is None else (self.b(group), self.d(group))
        pts = np.asarray(lam, dtype=complex)
        out = []
        for z in np.atleast_1d(pts):
            P = z * self.E - self.A
            if self.n and np.linalg.cond(P) > 1.0 / (self.n * np.finfo(float).eps):
                raise ModelError(f"λ = {z} is a pole of the model (λE − A is singular); evaluate elsewhere")
            out.append(self.C @ np.linalg.solve(P, B) + D if self.n else D.astype(complex))
        res = np.array(out, dtype=complex).reshape(-1, self.p, B.shape[1])
        return res[0] if pts.ndim == 0 else res

    def freqresp(self, omega, group: str | None = None) -> np.ndarray:
        """Frequency response at ``omega`` [rad/s]: ``G(jω)``, or ``G(e^{jω dt})`` in discrete time.

        Parameters
        ----------
        omega : array_like
            Frequencies [rad/s].
        group : str, optional
            One input group; default all inputs.

        Returns
        -------
        numpy.ndarray
            Complex ``(len(omega), p, k)``.

        Examples
        --------
        >>> m = DescriptorModel([[-1.0]], [[1.0]], Bu=[[1.0]])
        >>> round(abs(complex(m.freqresp([1.0])[0, 0, 0])), 6)
        0.707107
        """
        omega = validate.as_vector("omega (rad/s)", omega)
        z = np.exp(1j * omega * self.dt) if self.is_discrete else 1j * omega
        return self.evaluate(z, group).reshape(len(omega), self.p, -1)

    def poles(self, tol: float | None = None) -> np.ndarray:
        """The finite poles: finite generalised eigenvalues of ``A − λE`` (infinite ones split off first).

        The infinite eigenvalues are separated by the orthogonal staircase
        (:func:`fdikit.descriptor.staircase.pencil_structure`), not by a threshold on ``β`` in ``(α, β)`` pairs,
        so non-simple infinite eigenvalues do not turn into large finite ones.

        Parameters
        ----------
        tol : float, optional
            Relative rank tolerance of the staircase.

        Returns
        -------
        numpy.ndarray
            Complex poles, sorted.

        Examples
        --------
        >>> m = DescriptorModel([[-2.0, 0.0], [0.0, 1.0]], [[1.0, 1.0]], E=[[1.0, 0.0], [0.0, 0.0]])
        >>> m.poles().real.tolist()
        [-2.0]
        """
        if self.n == 0:
            return np.zeros(0, complex)
        return pencil_structure(self.A, self.E, tol=tol).finite_eigenvalues

    # ------------------------------------------------------------------ conversion
    @classmethod
    def from_fault_model(cls, model: FaultModel, *, E=None) -> DescriptorModel:
        """The descriptor form of a :class:`fdikit.model.FaultModel` (``E = I``, no ``aux`` inputs).

        Parameters
        ----------
        model : FaultModel
            The model; its names, groups and sample time are kept (its operating point is not carried).
        E : array_like, optional
            Use ``E`` and ``E A``, ``E B`` instead (an equivalent descriptor form, e.g. for tests); default ``I``.

        Returns
        -------
        DescriptorModel

        Raises
        ------
        ModelError
            If ``model`` is not a FaultModel.

        Examples
        --------
        >>> from fdikit import FaultModel
        >>> fm = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]], controls=["u"]).with_actuator_faults(["u"])
        >>> DescriptorModel.from_fault_model(fm).faults
        ('u_actuator',)
        """
        if not isinstance(model, FaultModel):
            raise ModelError(f"from_fault_model takes a fdikit.model.FaultModel, got {type(model).__name__}")
        T = np.eye(model.n) if E is None else validate.as_matrix("E", E, (model.n, model.n), error=ModelError)
        kw = {"E": T, "A": T @ model.A, "C": model.C, "dt": model.dt, "states": model.states,
              "outputs": model.outputs}
        for g in ("u", "d", "f", "w"):
            kw[f"B{g}"], kw[f"D{g}"], kw[_WORD[g]] = T @ model.b(g), model.d(g), model.inputs[g]
        return cls(**kw)

    def to_fault_model(self, *, aux: str = "error", tol: float | None = None) -> FaultModel:
        """The equivalent :class:`fdikit.model.FaultModel` (same transfer matrix), for a proper model.

        ``E`` invertible: ``(E⁻¹A, E⁻¹B, C, D)``, the states keep their names.  ``E`` singular: the non-dynamic
        modes are eliminated (:func:`fdikit.descriptor.reduction.remove_nondynamic`, the feedthrough ``D``
        updated); if ``E`` is still singular, uncontrollable and unobservable infinite eigenvalues are removed
        (:func:`fdikit.descriptor.reduction.minimal_realization`); the states are then new coordinates
        ``x0, x1, ...``.  An ``E`` that stays singular means controllable and observable infinite eigenvalues
        of higher index: an impulsive, improper model with a polynomial part — no ``FaultModel`` has that.

        Parameters
        ----------
        aux : {"error", "drop"}, default "error"
            What to do with auxiliary inputs, which a FaultModel has no group for: refuse, or drop them.
        tol : float, optional
            Relative rank tolerance of the reductions.

        Returns
        -------
        FaultModel

        Raises
        ------
        ModelError
            If the model is improper (the message gives the Jordan blocks at infinity left), or has ``aux``
            inputs with ``aux="error"``.
        ParameterError
            For an unknown ``aux`` option.

        Examples
        --------
        >>> m = DescriptorModel([[-1.0, 0.0], [1.0, -1.0]], [[0.0, 1.0]], E=[[1.0, 0.0], [0.0, 0.0]],
        ...                     Bu=[[1.0], [0.0]])
        >>> fm = m.to_fault_model()
        >>> fm.n, float(round(fm.poles()[0].real, 12))
        (1, -1.0)
        """
        validate.choice("aux", aux, ("error", "drop"))
        model = self
        if self.aux:
            if aux == "error":
                raise ModelError(f"the model has auxiliary inputs {list(self.aux)}, which a FaultModel has no group "
                                 "for; pass aux='drop' or move them to another group")
            model = _without_aux(self)
        from fdikit.descriptor.reduction import minimal_realization, remove_nondynamic

        states: Sequence[str] | None = model.states
        if not _invertible(model.E, tol):
            model, states = remove_nondynamic(model, tol=tol), None
            if not _invertible(model.E, tol):
                model = minimal_realization(model, tol=tol)
        if not _invertible(model.E, tol):
            blocks = pencil_structure(model.A, model.E, tol=tol).infinite_blocks
            raise ModelError(
                f"the model is improper: {model.n - np.linalg.matrix_rank(model.E)} infinite eigenvalues of A − λE "
                f"in Jordan blocks of sizes {list(blocks)} are controllable and observable (higher index, impulsive "
                "modes: the transfer matrix has a polynomial part), which a FaultModel cannot represent; keep the "
                "DescriptorModel, or make the plant proper (add the missing dynamics, e.g. a filter on the "
                "differentiated signal)")
        A = np.linalg.solve(model.E, model.A) if model.n else model.A
        B = np.linalg.solve(model.E, model.B) if model.n else model.B
        kw = {"A": A, "C": model.C, "dt": model.dt, "states": states, "outputs": model.outputs}
        for g in ("u", "d", "f", "w"):
            sl = model._slice(g)
            kw[f"B{g}"], kw[f"D{g}"], kw[_WORD[g]] = B[:, sl], model.D[:, sl], model.inputs[g]
        return FaultModel(**kw)

    def __repr__(self) -> str:
        kind = "continuous" if self.dt is None else f"discrete dt={self.dt:g}"
        groups = ", ".join(f"{g}={len(self.inputs[g])}" for g in DESCRIPTOR_GROUPS)
        return f"DescriptorModel({kind}, n={self.n}, p={self.p}, {groups})"


def _without_aux(model: DescriptorModel) -> DescriptorModel:
    kw = {"E": model.E, "A": model.A, "C": model.C, "dt": model.dt, "states": model.states,
          "outputs": model.outputs}
    for g in ("u", "d", "f", "w"):
        kw[f"B{g}"], kw[f"D{g}"], kw[_WORD[g]] = model.b(g), model.d(g), model.inputs[g]
    return DescriptorModel(**kw)


def _invertible(E: np.ndarray, tol: float | None) -> bool:
    """Whether ``E`` is invertible to the relative tolerance (``σ_min > tol · σ_max``)."""
    n = E.shape[0]
    if n == 0:
        return True
    s = np.linalg.svd(E, compute_uv=False)
    rtol = n * n * np.finfo(float).eps if tol is None else tol
    return bool(s[-1] > rtol * s[0]) if s[0] > 0 else False
