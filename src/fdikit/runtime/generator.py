"""Compiled online residual generation: :class:`CompiledGenerator`, the stepper for deployment.

One compiled call per sample computes ``[z+; r] = [A B; C D] [z; v]`` with ``v = [u − u0; y − y0]`` (the filter
of :class:`fdikit.residuals.ResidualGenerator`), checking the lengths and the finiteness of the inputs.  The
rare samples the compiled step does not take — a NaN/inf (a dropout), ``valid=False``, inputs that are not
1-D float64 arrays (lists, mappings by name), and the recovering samples after a gap — are stepped by the
reference :class:`fdikit.residuals.ResidualStepper` on the same filter state, so its gap rule, its recovery
flags and its error messages hold unchanged (Douglas et al. 1996 §4.2 for the filters; the gap rule is
:mod:`fdikit.gaps`).  The results equal the reference's to rounding (the products are summed in another order).

Why hand-written: the per-sample cost of the reference stepper is call overhead — input checks, small numpy
calls, a new array per sample — not arithmetic; numba removes it.  The kernel is compiled with an explicit
signature (``cache=True``), so an argument of any other type is refused, not reinterpreted.

Examples
--------
>>> import numpy as np
>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
>>> s = compile_generator(g)
>>> [round(float(s.step(np.ones(1), np.array([y]))[0]), 6) for y in (0.0, 1.0, 1.9, 3.71)]
[0.0, 0.0, 0.0, 1.0]
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np

from fdikit.errors import ParameterError
from fdikit.residuals import ResidualGenerator

__all__ = ["CompiledGenerator", "compile_generator", "filter_step"]


_IN = numba.types.Array(numba.types.float64, 1, "C", readonly=True)  # read-only inputs accept writable arrays
_MAT = numba.types.Array(numba.types.float64, 2, "C", readonly=True)
_BUF = numba.types.float64[::1]


@numba.njit(numba.types.int64(_MAT, _BUF, _IN, _IN, _IN, _BUF, numba.types.int64, numba.types.int64), cache=True,
            nogil=True)
def filter_step(MT, z, u, y, off, out, n, mu):  # pragma: no cover - compiled
    """``out = [A B; C D] [z; v]``, ``z[:n] ← out[:n]``; status 0, 1 for a non-finite input, -1 for wrong lengths.

    ``MT`` is ``[A B; C D]ᵀ`` (columns of the filter as rows, so the inner loop runs over contiguous memory),
    ``z`` the work vector ``[x; v]`` (``v`` the last valid inputs), ``off`` the operating point ``[u0; y0]``,
    ``mu`` the number of controls.
    """
    nv = MT.shape[0] - n
    if u.shape[0] != mu or y.shape[0] != nv - mu:
        return -1
    for j in range(mu):  # z[n:] keeps the last valid inputs (the gap rule holds them): check before writing
        if not np.isfinite(u[j] - off[j]):
            return 1
    for j in range(nv - mu):
        if not np.isfinite(y[j] - off[mu + j]):
            return 1
    for j in range(mu):
        z[n + j] = u[j] - off[j]
    for j in range(nv - mu):
        z[n + mu + j] = y[j] - off[mu + j]
    q = out.shape[0]
    for i in range(q):
        out[i] = 0.0
    for j in range(n + nv):
        zj = z[j]
        for i in range(q):
            out[i] += MT[j, i] * zj
    for i in range(n):
        z[i] = out[i]
    return 0


class CompiledGenerator:
    """A residual generator's online step, compiled; the reference stepper takes the rare samples.

    Parameters
    ----------
    generator : ResidualGenerator
        The filter (a continuous one needs ``dt``; it is ZOH-discretised as by ``generator.online``).
    x0 : array_like, optional
        Initial filter state (default zeros).
    dt : float, optional
        Sample time for a continuous generator.
    residual_cov, recovery_tol
        The gap rule's options, as in :meth:`fdikit.residuals.ResidualGenerator.run`.
    select : sequence of str, optional
        The residuals ``step`` returns, in this order (default all, in the generator's order).

    Attributes
    ----------
    reference : ResidualStepper
        The reference stepper that takes the samples the compiled step does not (same filter state).
    names : tuple of str
        The residuals ``step`` returns.

    Raises
    ------
    ParameterError
        For something other than a ResidualGenerator, an unknown name in ``select``, or a bad option.
    ModelError
        For a continuous generator without ``dt``.

    Examples
    --------
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> s = CompiledGenerator(g)
    >>> s.step(np.ones(1), np.array([np.nan])).tolist(), s.last_valid, s.invalid
    ([nan], False, 1)
    """

    def __init__(self, generator: ResidualGenerator, x0=None, dt: float | None = None, *, residual_cov=None,
                 recovery_tol: float = 0.1, select: Sequence[str] | None = None) -> None:
        if not isinstance(generator, ResidualGenerator):
            raise ParameterError(f"generator must be a fdikit.residuals.ResidualGenerator, got "
                                 f"{type(generator).__name__}")
        ref = generator.online(x0, dt, residual_cov=residual_cov, recovery_tol=recovery_tol)
        g = ref.generator
        names = g.residuals if select is None else tuple(select)
        unknown = [nm for nm in names if nm not in g.residuals]
        if unknown or isinstance(select, str):
            raise ParameterError(f"select names residuals {unknown or select!r} the generator does not have; it has "
                                 f"{list(g.residuals)}")
        order = [g.residuals.index(nm) for nm in names]
        order += [i for i in range(len(g.residuals)) if i not in order]
        self.reference = ref
        self.generator = g
        self.names = names
        self._order = np.array(order, dtype=np.int64)
        n = g.n
        self._n, self._mu = n, len(g.controls)
        self._MT = np.ascontiguousarray(np.block([[g.A, g.B], [g.C[order], g.D[order]]]).T)
        self._off = np.array(g.offset, dtype=float)
        self._MT.setflags(write=False)
        self._off.setflags(write=False)
        self._z = np.zeros(n + g.B.shape[1])
        self._out = np.zeros(n + len(order))
        self._r = self._out[n : n + len(names)]
        self._slow = False
        self.reset()

    def reset(self, x0=None) -> None:
        """Start again: the initial state (``x0``, else the one given at creation), no gap history.

        Parameters
        ----------
        x0 : array_like, optional
            A new initial filter state.

        Raises
        ------
        ParameterError
            For a bad ``x0``.
        """
        self.reference.reset(x0)
        self._z[: self._n] = self.reference.x
        self._z[self._n :] = self.reference.last_inputs
        self._slow = False

    @property
    def x(self) -> np.ndarray:
        """The current filter state (a copy)."""
        return self._z[: self._n].copy()

    @property
    def last_valid(self) -> bool:
        """Whether the last sample may be used for decisions (the reference gap rule's flag)."""
        return self.reference.last_valid

    @property
    def last_recovering(self) -> bool:
        """Whether the last sample was finite but still recovering from a gap."""
        return self.reference.last_recovering

    @property
    def invalid(self) -> int:
        """The number of invalid samples since creation or :meth:`reset`."""
        return self.reference.invalid

    def step(self, u, y) -> np.ndarray:
        """Residuals for one sample (absolute signals when the generator has an operating point).

        Parameters
        ----------
        u, y : numpy.ndarray of float64, or sequence, or mapping of name to float
            The controls and outputs in the generator's order; 1-D float64 arrays take the compiled path,
            anything else is checked and converted by the reference stepper.

        Returns
        -------
        numpy.ndarray
            The residuals of ``names`` (NaN on an invalid sample).  It is the stepper's own buffer,
            overwritten by the next step: copy it to keep it.

        Raises
        ------
        DataError
            For values that are not numbers, a mapping with other names, or the wrong number of values.
        """
        if not self._slow:
            try:
                status = filter_step(self._MT, self._z, u, y, self._off, self._out, self._n, self._mu)
            except TypeError:
                status = 2
            if status == 0:
                return self._r
        return self._reference_step(u, y)

    def _reference_step(self, u, y) -> np.ndarray:
        """One sample by the reference stepper from the compiled state; the compiled path resumes when valid."""
        ref, n = self.reference, self._n
        ref.x = self._z[:n].copy()
        ref.last_inputs = self._z[n:].copy()
        r = ref.step(u, y)  # validates, applies the gap rule, tracks the recovery
        self._z[:n] = ref.x
        self._z[n:] = ref.last_inputs
        self._out[self._n :] = r[self._order]
        self._slow = not ref.last_valid
        return self._r


def compile_generator(generator: ResidualGenerator, x0=None, dt: float | None = None, **options) -> CompiledGenerator:
    """The compiled online stepper of a residual generator (:class:`CompiledGenerator`).

    Parameters
    ----------
    generator : ResidualGenerator
        The filter.
    x0 : array_like, optional
        Initial filter state.
    dt : float, optional
        Sample time for a continuous generator.
    **options
        ``residual_cov``, ``recovery_tol``, ``select`` of :class:`CompiledGenerator`.

    Returns
    -------
    CompiledGenerator

    Raises
    ------
    ParameterError
        As :class:`CompiledGenerator`.

    Examples
    --------
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.5]], [[1.0]], [[1.0]], [[0.0]], (), ("y",), ("r",), dt=1.0)
    >>> compile_generator(g).step(np.zeros(0), np.ones(1)).tolist()
    [0.0]
    """
    return CompiledGenerator(generator, x0, dt, **options)

