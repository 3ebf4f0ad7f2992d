"""Identification data: traces split into usable segments, with the operating point removed.

Every identification routine of :mod:`fdikit.identify` reads its data through :func:`segments`.
A sample is usable when every control and output it reads is finite and the trace's
``valid`` flag is True; an unusable sample ends a segment (the samples on either side are never
joined, so no difference equation spans a gap).  A segment too short for the method is dropped
with an :class:`~fdikit.errors.FdiWarning` that counts the samples lost; when no segment is
left a :class:`~fdikit.errors.DataError` says how long a segment must be.  Nothing unusable is
ever silently used.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit import validate
from fdikit.errors import DataError, FdiWarning
from fdikit.trace import Trace

__all__ = ["IdentificationData", "segments"]


@dataclass(frozen=True)
class IdentificationData:
    """Usable segments of one or more traces, with the means removed.

    Attributes
    ----------
    u, y : list of (N_s, m) and (N_s, p) arrays
        Controls and outputs of each segment, minus ``u_mean`` and ``y_mean``.
    controls, outputs : tuple of str
        The names of the columns.
    dt : float
        The common sample time of the traces.
    u_mean, y_mean : (m,) and (p,) arrays
        The means removed (over every usable sample of every segment kept; zeros with ``detrend=False``).
    dropped : int
        Usable samples lost in segments that were too short.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.trace import Trace
    >>> tr = Trace(t=np.arange(4) * 0.5, u=np.ones((4, 1)), y=np.arange(4.0)[:, None], controls=["u"], outputs=["y"])
    >>> d = segments(tr)
    >>> d.dt, d.samples, d.y_mean.tolist()
    (0.5, 4, [1.5])

    References
    ----------
    Van Overschee & De Moor 1996, Ch. 4 (the Hankel matrices need gap-free stretches).
    """

    u: list
    y: list
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    dt: float
    u_mean: np.ndarray
    y_mean: np.ndarray
    dropped: int = 0

    @property
    def samples(self) -> int:
        """Number of samples used (all segments)."""
        return int(sum(len(s) for s in self.y))


def _runs(ok: np.ndarray) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of True in ``ok`` (stop exclusive)."""
    edges = np.diff(np.concatenate(([0], ok.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def segments(data, controls: Sequence[str] | None = None, outputs: Sequence[str] | None = None, *,
             min_length: int = 2, detrend: bool = True) -> IdentificationData:
    """Split traces at unusable samples (NaN, inf, ``valid == False``) and remove the means.

    Parameters
    ----------
    data : Trace or sequence of Trace
        One experiment or several (same sample time; each is split on its own).
    controls, outputs : sequence of str, optional
        The signals to read (default: those of the first trace).
    min_length : int >= 2, default 2
        Shortest segment kept; shorter ones are dropped with an :class:`FdiWarning`.
    detrend : bool, default True
        Remove the mean of each signal (pooled over the segments kept).

    Returns
    -------
    IdentificationData
        The segments, the names, ``dt``, the means and the count of samples dropped.

    Raises
    ------
    DataError
        When ``data`` holds no trace, a trace lacks a signal, the traces' sample times differ
        or a trace is not uniformly sampled, or no segment of ``min_length`` samples is left.
    ParameterError
        For a bad ``min_length``.

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.trace import Trace
    >>> y = np.arange(10.0).reshape(-1, 1); y[4] = np.nan
    >>> tr = Trace(t=np.arange(10) * 0.1, u=np.ones((10, 1)), y=y, controls=["u"], outputs=["y"])
    >>> d = segments(tr, min_length=3)
    >>> [len(s) for s in d.y], d.y_mean.tolist()
    ([4, 5], [4.555555555555555])

    References
    ----------
    Van Overschee & De Moor 1996, Ch. 4 (the Hankel matrices need gap-free stretches).
    """
    min_length = validate.integer("min_length", min_length, minimum=2)
    traces = [data] if isinstance(data, Trace) else list(data) if isinstance(data, Sequence) else None
    if not traces or not all(isinstance(tr, Trace) for tr in traces):
        raise DataError("identification data must be a Trace or a non-empty list of Traces "
                        f"(got {type(data).__name__}); one Trace per experiment")
    controls = tuple(traces[0].controls if controls is None else controls)
    outputs = tuple(traces[0].outputs if outputs is None else outputs)
    if not outputs:
        raise DataError("identification needs at least one output; pass outputs=[...]")
    dt = None
    us, ys, dropped = [], [], 0
    for k, tr in enumerate(traces):
        if len(tr) < 2:
            raise DataError(f"trace {k} has {len(tr)} samples; identification needs a sampled run")
        step = np.diff(tr.t)
        if np.ptp(step) > 1e-6 * np.median(step):
            raise DataError(f"trace {k} is not uniformly sampled (steps from {step.min():g} to {step.max():g} s); "
                            "resample it onto a uniform grid first")
        dt = tr.dt if dt is None else dt
        if abs(tr.dt - dt) > 1e-9 * dt:
            raise DataError(f"trace {k} has sample time {tr.dt:g} s but trace 0 has {dt:g} s; identify from traces "
                            "with one sample time (resample them)")
        u, y = tr.columns("u", controls), tr.columns("y", outputs)
        ok = np.all(np.isfinite(u), axis=1) & np.all(np.isfinite(y), axis=1)
        valid = getattr(tr, "valid", None)
        if valid is not None:
            ok &= np.asarray(valid, dtype=bool)
        for a, b in _runs(ok):
            if b - a < min_length:
                dropped += b - a
                continue
            us.append(u[a:b])
            ys.append(y[a:b])
    if not ys:
        raise DataError(f"no segment of at least {min_length} consecutive usable samples (finite controls and "
                        "outputs, valid == True) in the data; the method needs longer gap-free stretches (a shorter "
                        "horizon lowers the length it needs)")
    if dropped:
        warnings.warn(f"{dropped} usable samples in segments shorter than {min_length} samples were not used "
                      "(gaps split the traces; a shorter horizon keeps them)", FdiWarning, stacklevel=3)
    m, p = len(controls), len(outputs)
    u_mean = np.concatenate(us).mean(axis=0) if detrend and m else np.zeros(m)
    y_mean = np.concatenate(ys).mean(axis=0) if detrend else np.zeros(p)
    return IdentificationData([u - u_mean for u in us], [y - y_mean for y in ys], controls, outputs, float(dt),
                              u_mean, y_mean, dropped)
