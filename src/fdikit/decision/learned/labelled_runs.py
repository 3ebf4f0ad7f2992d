"""Labelled residual runs as training data, and residual rows as classifier inputs (Douglas et al. 1996, §6.2–6.4).

Shared by the Bayesian neural network (:mod:`fdikit.decision.learned.bnn`) and the Gaussian ML classifier
(:mod:`fdikit.decision.learned.gaussian_ml`): the input map (one magnitude per fault group, or raw residuals;
§5.1.1), the training-data forms (a mapping label → runs, or runs with per-sample labels), the one-hot targets of
§6.2.2 and the decision rule on posterior probabilities.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from fdikit.diagnosis import Diagnosis
from fdikit.errors import DataError, ParameterError
from fdikit.faults import NO_FAULT
from fdikit.residuals import Residuals

__all__ = ["LabelledInputs", "as_runs", "one_hot_targets", "posterior_decisions"]


@dataclass(frozen=True)
class LabelledInputs:
    """How a residual row becomes the network/classifier input."""

    n_columns: int
    groups: tuple[tuple[int, ...], ...]
    keys: tuple[str, ...]
    magnitude: bool
    scale: np.ndarray

    @classmethod
    def build(cls, names, isolates, mode: str, columns) -> LabelledInputs:
        if mode not in ("magnitude", "raw"):
            raise ParameterError(f"unknown inputs mode {mode!r}; use 'magnitude' or 'raw'")
        names = tuple(names)
        if columns is None:
            idx = list(range(len(names)))
        else:
            missing = [c for c in columns if c not in names]
            if missing:
                raise DataError(f"columns {missing} are not among the residuals {list(names)}")
            idx = [names.index(c) for c in columns]
        key = [isolates[i] if isolates[i] is not None else names[i] for i in idx]
        if mode == "raw":
            groups, keys = tuple((i,) for i in idx), tuple(key)
        else:
            keys = tuple(dict.fromkeys(key))
            groups = tuple(tuple(i for i, kk in zip(idx, key) if kk == k) for k in keys)
        return cls(len(names), groups, keys, mode == "magnitude", np.ones(len(keys)))

    def raw(self, r: np.ndarray) -> np.ndarray:
        r = np.asarray(r, dtype=float)
        if r.shape[-1] != self.n_columns:
            raise DataError(f"residual vector has {r.shape[-1]} entries, the evaluator was set up for {self.n_columns}")
        if self.magnitude:
            return np.stack([np.sqrt(np.sum(r[..., list(g)] ** 2, axis=-1)) for g in self.groups], axis=-1)
        return r[..., [g[0] for g in self.groups]]

    def __call__(self, r: np.ndarray) -> np.ndarray:
        return self.raw(r) / self.scale


def as_runs(data, labels) -> list[tuple[Residuals, np.ndarray]]:
    """Training data as (residuals, per-sample labels) pairs."""
    runs: list[tuple[Residuals, np.ndarray]] = []
    if isinstance(data, Mapping):
        if labels is not None:
            raise ParameterError(
                "give labels only with a sequence of Residuals; a mapping's keys are the labels"
            )
        for key, value in data.items():
            items = [value] if isinstance(value, Residuals) else list(value)
            for res in items:
                if not isinstance(res, Residuals):
                    raise DataError(f"training data for {key!r} must be Residuals, got {type(res).__name__}")
                runs.append((res, np.full(len(res), str(key), dtype=object)))
    else:
        items = [data] if isinstance(data, Residuals) else list(data)
        if labels is None:
            raise ParameterError("a sequence of Residuals needs per-run labels (a str or one label per sample)")
        labels = [labels] if isinstance(labels, str) or isinstance(data, Residuals) else list(labels)
        if len(labels) != len(items):
            raise DataError(f"{len(labels)} label entries for {len(items)} runs")
        for res, lab in zip(items, labels):
            if not isinstance(res, Residuals):
                raise DataError(f"training data must be Residuals, got {type(res).__name__}")
            lab = np.full(len(res), lab, dtype=object) if isinstance(lab, str) else np.asarray(lab, dtype=object)
            if lab.shape != (len(res),):
                raise DataError(f"labels have shape {lab.shape}, the run has {len(res)} samples")
            runs.append((res, lab.astype(str).astype(object)))
    if not runs:
        raise DataError("no training data; pass {'none': fault-free residuals, fault: residuals, ...}")
    names = runs[0][0].names
    for res, _ in runs:
        if res.names != names:
            raise DataError(f"training residuals differ in their names: {list(res.names)} vs {list(names)}")
    return runs


def one_hot_targets(labels: np.ndarray, hypotheses: tuple[str, ...]) -> np.ndarray:
    """One-hot targets (§6.2.2): zeros for 'none' and for faults outside the hypotheses."""
    Z = np.zeros((labels.size, len(hypotheses)))
    for j, h in enumerate(hypotheses):
        Z[:, j] = [h in str(lab).split("+") for lab in labels]
    return Z


def posterior_decisions(t, P, valid, hypotheses, threshold, meta) -> Diagnosis:
    fired = P >= threshold
    alarm = fired.any(axis=1)
    isolated = np.where(alarm, np.asarray(hypotheses, dtype=object)[np.argmax(P, axis=1)], NO_FAULT).astype(str)
    return Diagnosis(t, alarm, fired, hypotheses, isolated, probabilities=P, hypotheses=hypotheses, valid=valid,
                     meta=meta)
