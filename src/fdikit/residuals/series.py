"""Residual time series: :class:`Residuals`, what a residual generator's ``run`` returns.

The series, the residual names, the fault each residual is tied to and the validity of every sample
(invalid input samples and the *recovering* samples after a gap, :mod:`fdikit.gaps`).  Part of the package
:mod:`fdikit.residuals`, with the generators that produce it (:mod:`fdikit.residuals.generator`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from fdikit.errors import DataError

__all__ = ["Residuals"]


@dataclass(frozen=True, eq=False)
class Residuals:
    """Residual time series.

    Constructed with the attributes below, in that order (``valid``, ``meta`` and ``recovering`` optional);
    the arrays are converted to float / bool and their sizes checked.

    Attributes
    ----------
    t : (N,) numpy.ndarray
        Sample times [s].
    r : (N, q) numpy.ndarray
        Residuals (NaN on invalid samples).
    names : tuple of str
        Residual names (q of them).
    isolates : tuple of (str or None)
        Per residual, the fault it is tied to (None = detection only); ``()`` means all None.
    valid : (N,) numpy.ndarray of bool
        True where the residuals may be used for decisions: False on an invalid input sample
        (``r`` NaN) and on the *recovering* samples after a gap; default all True.
    meta : dict
        Free-form metadata (a generator's ``run`` stores the trace's metadata under ``"trace"``).
    recovering : (N,) numpy.ndarray of bool
        True on the finite samples after a gap whose gap transient has not yet decayed below the
        noise (see :class:`~fdikit.residuals.ResidualStepper`); these are also not ``valid``.
        Default all False.

    Raises
    ------
    DataError
        If ``r`` is not (N, q) for N times and q names, or ``isolates``, ``valid`` or ``recovering``
        has the wrong length.

    Examples
    --------
    >>> res = Residuals(np.arange(4) * 0.1, np.zeros((4, 2)), ("r1", "r2"), (None, "f1_sensor"))
    >>> len(res), res.r.shape, res.isolates, bool(res.valid.all())
    (4, (4, 2), (None, 'f1_sensor'), True)
    """

    t: np.ndarray
    r: np.ndarray
    names: tuple[str, ...]
    isolates: tuple[str | None, ...]
    valid: np.ndarray | None = None
    meta: dict = field(default_factory=dict)
    recovering: np.ndarray | None = None

    def __post_init__(self) -> None:
        r = np.atleast_2d(np.asarray(self.r, dtype=float))
        t = np.asarray(self.t, dtype=float).ravel()
        if r.shape != (t.size, len(self.names)):
            raise DataError(f"residuals have shape {r.shape}, need ({t.size}, {len(self.names)})")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "r", r)
        object.__setattr__(self, "names", tuple(self.names))
        isolates = tuple(self.isolates) if self.isolates else (None,) * len(self.names)
        if len(isolates) != len(self.names):
            raise DataError(f"{len(isolates)} 'isolates' entries for {len(self.names)} residuals")
        object.__setattr__(self, "isolates", isolates)
        valid = np.ones(t.size, bool) if self.valid is None else np.asarray(self.valid, bool).ravel()
        rec = np.zeros(t.size, bool) if self.recovering is None else np.asarray(self.recovering, bool).ravel()
        if valid.shape != t.shape or rec.shape != t.shape:
            raise DataError(f"residuals 'valid'/'recovering' flags have {valid.size}/{rec.size} entries for "
                            f"{t.size} samples")
        object.__setattr__(self, "valid", valid)
        object.__setattr__(self, "recovering", rec)

    def __len__(self) -> int:
        return self.t.size

    def slice(self, start: float | None = None, stop: float | None = None) -> Residuals:
        """The samples with ``start <= t < stop``.

        Parameters
        ----------
        start, stop : float, optional
            Time bounds [s]; None means unbounded.

        Returns
        -------
        Residuals
            The selected samples with their flags (the metadata copied).

        Examples
        --------
        >>> Residuals(np.arange(5.0), np.zeros((5, 1)), ("r",), ()).slice(1.0, 3.0).t.tolist()
        [1.0, 2.0]
        """
        mask = np.ones(self.t.size, bool)
        if start is not None:
            mask &= self.t >= start
        if stop is not None:
            mask &= self.t < stop
        return Residuals(self.t[mask], self.r[mask], self.names, self.isolates, self.valid[mask], dict(self.meta),
                         self.recovering[mask])

    def select(self, names: Sequence[str]) -> Residuals:
        """The residuals ``names``, in that order (e.g. to match the order an evaluator was fitted on).

        Raises :class:`DataError` naming the residuals that are not in the series.

        Parameters
        ----------
        names : str or sequence of str
            Residual names of this series.

        Returns
        -------
        Residuals
            The same samples and flags with only these residuals (and their ``isolates``).

        Raises
        ------
        DataError
            If a name is not in the series.

        Examples
        --------
        >>> res = Residuals(np.arange(3.0), np.ones((3, 2)) * [1.0, 2.0], ("a", "b"), ())
        >>> res.select(["b"]).names, res.select(["b"]).r[:, 0].tolist()
        (('b',), [2.0, 2.0, 2.0])
        """
        names = (names,) if isinstance(names, str) else tuple(names)
        missing = [nm for nm in names if nm not in self.names]
        if missing:
            raise DataError(f"residuals {missing} are not in the series (it has {list(self.names)})")
        idx = [self.names.index(nm) for nm in names]
        return Residuals(self.t, self.r[:, idx], names, tuple(self.isolates[i] for i in idx), self.valid,
                         dict(self.meta), self.recovering)

    def to_pandas(self):
        """The series as a :class:`pandas.DataFrame`: one column per residual plus ``valid`` and ``recovering``.

        Returns
        -------
        pandas.DataFrame
            Indexed by ``t`` (index name ``"t"``); columns the residual names, ``valid``, ``recovering``.
        """
        import pandas as pd

        df = pd.DataFrame(self.r, columns=list(self.names), index=pd.Index(self.t, name="t"))
        df["valid"] = self.valid
        df["recovering"] = self.recovering
        return df

    def plot(self, ax=None, **kwargs):
        """Draw the residuals, one panel each (:func:`fdikit.plots.plot_residuals`).

        Parameters
        ----------
        ax : matplotlib Axes or sequence of Axes, optional
            One Axes per residual, or one for all; default a new figure.
        **kwargs
            ``diagnosis``, ``thresholds``, ``center``, ``onset``, ``names``, ``title`` and ``path``
            of :func:`~fdikit.plots.plot_residuals`.

        Returns
        -------
        matplotlib.figure.Figure or the given ``ax``
            A new figure when ``ax`` is None, else ``ax``.

        Examples
        --------
        >>> import matplotlib.pyplot as plt
        >>> fig, ax = plt.subplots()
        >>> Residuals(np.arange(3.0), np.zeros((3, 1)), ("r",), ()).plot(ax=ax, thresholds=1.0) is ax
        True
        >>> plt.close(fig)
        """
        from fdikit.plots import plot_residuals

        return plot_residuals(self, ax=ax, **kwargs)
