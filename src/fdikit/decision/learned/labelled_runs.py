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
    """How a residual row becomes the network/classifier input.

    Calling the object maps residual rows ``(..., n_columns)`` to inputs ``(..., len(keys))``: per group, the
    Euclidean magnitude of its residuals (``magnitude``) or the residual itself (raw), divided by ``scale``.
    Build it with ``LabelledInputs.build(names, isolates, mode, columns)``: ``mode`` ``"magnitude"`` groups the
    residuals tied to the same fault (an untied one by its name), ``"raw"`` keeps one input per residual;
    ``columns`` (names, or None for all) selects the residuals used.

    Attributes
    ----------
    n_columns : int
        Number of residuals a row must have.
    groups : tuple of tuple of int
        Residual indices behind each input.
    keys : tuple of str
        Each input's name: the fault of its group, or the residual's name.
    magnitude : bool
        Whether an input is its group's magnitude (else the raw residual).
    scale : (len(keys),) ndarray
        Divisor of each input (ones from ``build``).

    References
    ----------
    Douglas et al. 1996, §5.1.1 (residual magnitudes per fault) and §6.4 (the residual process as the input of
    the Bayesian neural networks).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.learned.labelled_runs import LabelledInputs
    >>> inputs = LabelledInputs.build(("a0", "a1", "b"), ("fa", "fa", "fb"), "magnitude", None)
    >>> inputs.keys, inputs(np.array([3.0, 4.0, 1.0])).tolist()
    (('fa', 'fb'), [5.0, 1.0])
    """

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
    """Training data as (residuals, per-sample labels) pairs.

    Parameters
    ----------
    data : mapping, Residuals or sequence of Residuals
        ``{label: Residuals or sequence of Residuals}`` (the key labels every sample: ``"none"`` or a fault name,
        ``"fa+fb"`` for several), or runs whose labels come from ``labels``.
    labels : str, sequence or None
        None with a mapping; otherwise one entry per run: a label for the whole run, or an (N,) array of
        per-sample labels.

    Returns
    -------
    list of (Residuals, (N,) object ndarray)
        Each run with its per-sample labels as strings.

    Raises
    ------
    ParameterError
        When ``labels`` is given with a mapping, or missing with runs.
    DataError
        When an item is not a ``Residuals``, the numbers of runs and labels differ, a label array does not have
        one entry per sample, there is no data, or the runs differ in their residual names.

    References
    ----------
    Douglas et al. 1996, §6.4 (networks trained on simulated runs with and without each fault).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.residuals import Residuals
    >>> from fdikit.decision.learned.labelled_runs import as_runs
    >>> r = Residuals(np.arange(4) * 0.1, np.zeros((4, 1)), ("r",), ("f",))
    >>> [(len(res), str(lab[0])) for res, lab in as_runs({"none": r, "f": [r, r]}, None)]
    [(4, 'none'), (4, 'f'), (4, 'f')]
    """
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
    """One-hot targets (§6.2.2): zeros for 'none' and for faults outside the hypotheses.

    Parameters
    ----------
    labels : (N,) array of str
        Per-sample labels; ``"fa+fb"`` sets both columns.
    hypotheses : tuple of str
        The fault hypotheses, one output column each.

    Returns
    -------
    (N, len(hypotheses)) ndarray
        ``z_k``: 1 where the sample's label contains the hypothesis, else 0.

    References
    ----------
    Douglas et al. 1996, §6.2.2 (the desired output ``z_k``, a unit vector for class ``i``, zero outside the
    classes).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.learned.labelled_runs import one_hot_targets
    >>> one_hot_targets(np.array(["none", "fa", "fa+fb"], dtype=object), ("fa", "fb")).tolist()
    [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]
    """
    Z = np.zeros((labels.size, len(hypotheses)))
    for j, h in enumerate(hypotheses):
        Z[:, j] = [h in str(lab).split("+") for lab in labels]
    return Z


def posterior_decisions(t, P, valid, hypotheses, threshold, meta) -> Diagnosis:
    """The diagnosis from posterior probabilities: a hypothesis fires at or above ``threshold``.

    The alarm is on when any hypothesis fires; the isolated fault is then the most probable hypothesis (also
    when it is not the fired one), ``"none"`` otherwise.

    Parameters
    ----------
    t : (N,) ndarray
        Sample times [s].
    P : (N, m) ndarray
        Posterior probability of each fault hypothesis per sample.
    valid : (N,) bool ndarray
        Validity per sample (passed to the diagnosis).
    hypotheses : tuple of str
        The ``m`` fault names of the columns of ``P``.
    threshold : float or (m,) array_like
        Announcement probability per hypothesis.
    meta : dict
        Metadata of the diagnosis.

    Returns
    -------
    Diagnosis
        With ``fired = P >= threshold`` per hypothesis and ``probabilities = P``.

    References
    ----------
    Douglas et al. 1996, §6.2.2 (network outputs as posterior probabilities) and §6.4 (a fault announced with
    its probability).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.learned.labelled_runs import posterior_decisions
    >>> P = np.array([[0.1, 0.2], [0.7, 0.1]])
    >>> d = posterior_decisions(np.array([0.0, 0.1]), P, np.array([True, True]), ("fa", "fb"), 0.5, {})
    >>> d.alarm.tolist(), d.isolated.tolist()
    ([False, True], ['none', 'fa'])
    """
    fired = P >= threshold
    alarm = fired.any(axis=1)
    isolated = np.where(alarm, np.asarray(hypotheses, dtype=object)[np.argmax(P, axis=1)], NO_FAULT).astype(str)
    return Diagnosis(t, alarm, fired, hypotheses, isolated, probabilities=P, hypotheses=hypotheses, valid=valid,
                     meta=meta)
