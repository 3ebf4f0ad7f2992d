"""One logged run: time, controls, measurements, states and the true fault per sample.

A :class:`Trace` is what :func:`fdikit.simulate.simulate` returns and what residual
generators and evaluators consume.  It exports to pandas and saves to Parquet; the
round trip is exact (float64 columns, metadata as JSON in the schema).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fdikit.errors import DataError
from fdikit.faults import NO_FAULT

__all__ = ["Trace"]

_PREFIX = {"u": "u:", "y": "y:", "x": "x:", "d": "d:"}


def _block(name: str, value, n: int, names: Sequence[str]) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and len(names) == 1:
        arr = arr.reshape(-1, 1)
    if arr.shape != (n, len(names)):
        raise DataError(
            f"trace signal block {name!r} has shape {arr.shape} but must be ({n}, {len(names)}): "
            f"one row per sample and one column per name {list(names)}"
        )
    return arr


@dataclass(frozen=True, eq=False)
class Trace:
    """A sampled run.

    Attributes
    ----------
    t : (N,) sample times, strictly increasing.
    u, y : (N, m) controls as commanded, (N, p) measurements as recorded.
    x : (N, n) true states, or an (N, 0) array when unknown.
    d : (N, nd) disturbances, or (N, 0).
    fault : (N,) str, the true active fault per sample (``'none'`` where healthy).
    controls, outputs, states, disturbances : names of the columns.
    meta : dict of JSON-serialisable metadata (plant, seed, scenario label ...).
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    controls: tuple[str, ...]
    outputs: tuple[str, ...]
    x: np.ndarray | None = None
    states: tuple[str, ...] = ()
    d: np.ndarray | None = None
    disturbances: tuple[str, ...] = ()
    fault: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float).ravel()
        n = t.size
        if n and (not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0)):
            raise DataError("trace time t must be finite and strictly increasing")
        set_ = object.__setattr__
        set_(self, "t", t)
        for attr in ("controls", "outputs", "states", "disturbances"):
            set_(self, attr, tuple(getattr(self, attr)))
        set_(self, "u", _block("u", self.u, n, self.controls))
        set_(self, "y", _block("y", self.y, n, self.outputs))
        set_(self, "x", _block("x", np.zeros((n, 0)) if self.x is None else self.x, n, self.states))
        set_(self, "d", _block("d", np.zeros((n, 0)) if self.d is None else self.d, n, self.disturbances))
        fault = np.full(n, NO_FAULT) if self.fault is None else np.asarray(self.fault, dtype=str)
        if fault.shape != (n,):
            raise DataError(f"trace fault labels have shape {fault.shape}, need ({n},)")
        set_(self, "fault", fault)
        set_(self, "meta", dict(self.meta))

    # ------------------------------------------------------------------ access
    def __len__(self) -> int:
        return self.t.size

    @property
    def dt(self) -> float:
        """Sample time (median spacing)."""
        if self.t.size < 2:
            raise DataError("a trace with fewer than 2 samples has no sample time")
        return float(np.median(np.diff(self.t)))

    def names_of(self, kind: str) -> tuple[str, ...]:
        """Column names of block ``kind`` (``'u'``, ``'y'``, ``'x'`` or ``'d'``)."""
        names = {"u": self.controls, "y": self.outputs, "x": self.states, "d": self.disturbances}.get(kind)
        if names is None:
            raise DataError(f"unknown signal kind {kind!r}; use 'u', 'y', 'x' or 'd'")
        return names

    def signal(self, name: str, kind: str = "y") -> np.ndarray:
        """One column by name; ``kind`` is ``'u'``, ``'y'``, ``'x'`` or ``'d'``."""
        names = self.names_of(kind)
        if name not in names:
            raise DataError(f"the trace has no {kind}-signal named {name!r}; it has {list(names)}")
        return getattr(self, kind)[:, names.index(name)]

    def columns(self, kind: str, names: Sequence[str]) -> np.ndarray:
        """(N, len(names)) block of ``kind`` signals in the order of ``names``."""
        return np.column_stack([self.signal(nm, kind) for nm in names]) if names else np.zeros((len(self), 0))

    def check_finite(self, signals: Sequence[str] = ("u", "y")) -> None:
        """Raise :class:`DataError` naming the first NaN/inf sample of the given blocks."""
        for kind in signals:
            names = self.names_of(kind)
            block = getattr(self, kind)
            bad = np.argwhere(~np.isfinite(block))
            if bad.size:
                k, j = bad[0]
                raise DataError(
                    f"trace has a non-finite value in {kind}-signal {names[j]!r} at sample {k} (t={self.t[k]:g}); "
                    f"{int((~np.isfinite(block)).sum())} bad values in all. Clean or interpolate the data, or "
                    "process it online with step(), which skips bad samples"
                )

    @property
    def fault_onset(self) -> float | None:
        """Time of the first faulty sample, or None for a fault-free trace."""
        idx = np.flatnonzero(self.fault != NO_FAULT)
        return float(self.t[idx[0]]) if idx.size else None

    # ------------------------------------------------------------------ export and I/O
    def to_pandas(self):
        """A DataFrame indexed by time with columns ``u:<name>``, ``y:<name>``, ``x:...``, ``d:...``, ``fault``."""
        import pandas as pd

        data = {}
        for kind, names in (("u", self.controls), ("y", self.outputs), ("x", self.states), ("d", self.disturbances)):
            block = getattr(self, kind)
            for j, nm in enumerate(names):
                data[_PREFIX[kind] + nm] = block[:, j]
        data["fault"] = self.fault
        return pd.DataFrame(data, index=pd.Index(self.t, name="t"))

    def save(self, path: str | Path) -> Path:
        """Write to Parquet (metadata in the schema); the round trip with :meth:`load` is exact."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        table = pa.Table.from_pandas(self.to_pandas().reset_index(), preserve_index=False)
        info = {
            "controls": list(self.controls), "outputs": list(self.outputs), "states": list(self.states),
            "disturbances": list(self.disturbances), "meta": self.meta,
        }
        table = table.replace_schema_metadata({**(table.schema.metadata or {}), b"fdikit": json.dumps(info).encode()})
        pq.write_table(table, path)
        return path

    @classmethod
    def load(cls, path: str | Path) -> Trace:
        """Read a trace written by :meth:`save`."""
        import pyarrow.parquet as pq

        path = Path(path)
        if not path.exists():
            raise DataError(f"no trace file at {path}")
        table = pq.read_table(path)
        raw = (table.schema.metadata or {}).get(b"fdikit")
        if raw is None:
            raise DataError(f"{path} is a Parquet file but not an fdikit trace (no 'fdikit' schema metadata)")
        info = json.loads(raw)
        df = table.to_pandas()

        def block(kind: str, names: list[str]) -> np.ndarray:
            return df[[_PREFIX[kind] + nm for nm in names]].to_numpy(float) if names else np.zeros((len(df), 0))

        return cls(
            t=df["t"].to_numpy(float), u=block("u", info["controls"]), y=block("y", info["outputs"]),
            x=block("x", info["states"]), d=block("d", info["disturbances"]), controls=info["controls"],
            outputs=info["outputs"], states=info["states"], disturbances=info["disturbances"],
            fault=df["fault"].to_numpy(str), meta=info["meta"],
        )

    def __repr__(self) -> str:
        span = f"{self.t[0]:g}..{self.t[-1]:g} s" if len(self) else "empty"
        return (
            f"Trace({len(self)} samples, {span}, u={len(self.controls)}, y={len(self.outputs)}, "
            f"x={len(self.states)}, faults={sorted(set(self.fault.tolist()) - {NO_FAULT})})"
        )
