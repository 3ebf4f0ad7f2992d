"""Deployable detectors: a residual generator and a fitted evaluator, packaged to run on logs and online.

A :class:`Detector` holds what a deployment needs: the :class:`~fdikit.residuals.ResidualGenerator` (one
filter or a stacked bank), a fitted evaluator of :mod:`fdikit.decision`, the signals the generator reads,
how each is read from a log (unit and column: :meth:`Detector.read_log`), the operating point the generator
subtracts from the absolute signals, the gap options, and metadata (name, description, creation time,
fdikit version).  ``run(trace) -> Diagnosis`` is the batch; ``online()`` gives a :class:`DetectorStepper`
whose ``step(u, y)`` returns the evaluator's :class:`~fdikit.diagnosis.StepDecision`.  Bad samples (NaN)
and samples flagged invalid (``valid=False``, as ``trace.valid``) are gaps for the generator's gap rule
(:mod:`fdikit.gaps`); the evaluator holds its decision over them and over the recovering samples after
them, so online decisions are the batch ones.  ``save(path)`` / ``Detector.load(path)`` use the data-only,
digest-checked file of :mod:`fdikit.detector_file` (``docs/methods/deployment.md``).

Examples
--------
>>> import numpy as np
>>> from fdikit.decision import ThresholdEvaluator
>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
>>> ev = ThresholdEvaluator(thresholds=[0.5], isolates=("y_sensor",))
>>> det = Detector(g, ev, units={"y": "deg"}, name="demo")
>>> s = det.online()
>>> [s.step([1.0], [y]).fault for y in (0.0, 1.0, 1.9, 3.71)]
['none', 'none', 'none', 'y_sensor']
"""

from __future__ import annotations

import datetime
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from fdikit.errors import DataError, ParameterError

__all__ = ["Detector"]


def _names_map(what: str, value, signals: tuple[str, ...]) -> dict[str, str]:
    """A mapping signal -> non-empty string, every key a signal the generator reads."""
    if value is None:
        return {}
    if not isinstance(value, Mapping):
        raise ParameterError(f"{what} must be a mapping signal name -> string, got {type(value).__name__}")
    out = {}
    for k, v in value.items():
        if k not in signals:
            raise ParameterError(f"{what} names {k!r}, which the generator does not read; its signals are "
                                 f"{list(signals)}")
        if not isinstance(v, str) or not v:
            raise ParameterError(f"{what}[{k!r}] must be a non-empty string, got {v!r}")
        out[k] = v
    return out


def _text(what: str, value) -> str:
    if not isinstance(value, str):
        raise ParameterError(f"{what} must be a string, got {type(value).__name__}")
    return value


@dataclass(frozen=True, eq=False)
class Detector:
    """A residual generator and a fitted evaluator with what a deployment needs to run them.

    Parameters
    ----------
    generator : ResidualGenerator
        The filter (or stacked bank, :func:`fdikit.residuals.stack_generators`); it reads absolute signals and
        subtracts its ``operating_point``.
    evaluator : evaluator of :mod:`fdikit.decision`
        Fitted (ThresholdEvaluator, CusumEvaluator, GlrEvaluator, SprtEvaluator, MhsprtEvaluator,
        GaussianMlEvaluator, BnnEvaluator, Whitened ...).  When it was fitted on a subset or another order of the
        generator's residuals, the detector selects those (by name).
    units : mapping of str to str, optional
        Unit of each signal as read from a log (e.g. ``{"speed": "km/h"}``), for :meth:`read_log`.
    columns : mapping of str to str, optional
        Column of each signal in a log, when it differs from the signal's name.
    time_column : str, optional
        The log's time column (None: the importer's default).
    name, description : str
        Metadata.
    created : str, optional
        ISO 8601 creation time (default now, UTC).
    fdikit_version : str, optional
        The fdikit version that built the detector (default this one).
    residual_cov, recovery_tol
        The gap rule's options (:meth:`fdikit.residuals.ResidualGenerator.run`), used by ``run`` and ``online``.
    warmup : float, default 0.0
        Seconds at the start of a run (a trace, or an online stepper after :meth:`DetectorStepper.reset`) whose
        samples are not valid for decisions: the filter starts at the operating point, so a plant that is not
        there (a car already cornering) leaves an initial transient that decays with the filter's poles.

    Attributes
    ----------
    controls, outputs : tuple of str
        The signals the detector reads (the generator's).
    operating_point : OperatingPoint or None
        The generator's operating point.

    Raises
    ------
    ParameterError
        For a generator that is not a ResidualGenerator, an evaluator without ``run``/``step``/``reset``, a
        ``units``/``columns`` entry for a signal the generator does not read or a bad gap option.
    DataError
        When the evaluator was fitted on residuals the generator does not produce.

    Examples
    --------
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> det = Detector(g, ThresholdEvaluator(thresholds=[0.5]), columns={"y": "Y_LOG"})
    >>> det.controls, det.outputs, det.columns
    (('u',), ('y',), {'y': 'Y_LOG'})
    """

    generator: object
    evaluator: object
    units: dict = field(default_factory=dict)
    columns: dict = field(default_factory=dict)
    time_column: str | None = None
    name: str = "detector"
    description: str = ""
    created: str | None = None
    fdikit_version: str | None = None
    residual_cov: np.ndarray | None = None
    recovery_tol: float = 0.1
    warmup: float = 0.0

    def __post_init__(self) -> None:
        from fdikit import __version__
        from fdikit.residuals import ResidualGenerator

        set_ = object.__setattr__
        g = self.generator
        if not isinstance(g, ResidualGenerator):
            raise ParameterError(f"generator must be a fdikit.residuals.ResidualGenerator, got {type(g).__name__}")
        ev = self.evaluator
        missing = [m for m in ("run", "step", "reset") if not callable(getattr(ev, m, None))]
        if missing:
            raise ParameterError(f"evaluator {type(ev).__name__} lacks {missing}; give a fitted evaluator of "
                                 "fdikit.decision")
        signals = g.controls + g.outputs
        set_(self, "units", _names_map("units", self.units, signals))
        set_(self, "columns", _names_map("columns", self.columns, signals))
        if self.time_column is not None:
            _text("time_column", self.time_column)
        for what in ("name", "description"):
            _text(what, getattr(self, what))
        set_(self, "created", _text("created", self.created) if self.created is not None else
             datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"))
        set_(self, "fdikit_version",
             _text("fdikit_version", self.fdikit_version) if self.fdikit_version is not None else __version__)
        if self.residual_cov is not None:
            cov = np.array(self.residual_cov, dtype=float)
            cov.setflags(write=False)
            set_(self, "residual_cov", cov)
        if type(self.recovery_tol) is not float:
            set_(self, "recovery_tol", float(self.recovery_tol))
        from fdikit import validate

        set_(self, "warmup", float(validate.non_negative("warmup (seconds)", self.warmup)))
        if g.dt is not None:  # the gap options are checked now, not at the first gap of a deployment
            from fdikit.gaps import gap_options

            gap_options(g, self.residual_cov, self.recovery_tol)
        fitted = getattr(ev, "names", None)
        if fitted is None or tuple(fitted) == g.residuals:
            index = None
        else:
            unknown = [nm for nm in fitted if nm not in g.residuals]
            if unknown:
                raise DataError(f"the evaluator was fitted on residuals {unknown} that the generator does not "
                                f"produce (it produces {list(g.residuals)}); fit it on this generator's residuals")
            index = [g.residuals.index(nm) for nm in fitted]
        set_(self, "_index", index)

    # ------------------------------------------------------------------ signals
    @property
    def controls(self) -> tuple[str, ...]:
        """The controls the detector reads."""
        return self.generator.controls

    @property
    def outputs(self) -> tuple[str, ...]:
        """The outputs (measurements) the detector reads."""
        return self.generator.outputs

    @property
    def operating_point(self):
        """The generator's operating point (None when it has none)."""
        return getattr(self.generator, "operating_point", None)

    @property
    def residual_names(self) -> tuple[str, ...]:
        """The residuals the evaluator reads, in its order."""
        g = self.generator
        return g.residuals if self._index is None else tuple(g.residuals[i] for i in self._index)

    # ------------------------------------------------------------------ batch
    def residuals(self, trace):
        """The residuals of a trace the evaluator reads (batch; gaps and ``trace.valid`` as in the generator).

        Parameters
        ----------
        trace : Trace
            Absolute signals, holding every control and output the detector reads.

        Returns
        -------
        Residuals
            The generator's residuals, selected and ordered as the evaluator was fitted.

        Raises
        ------
        DataError
            On a missing signal or a sample time other than a discrete generator's.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> from fdikit.trace import Trace
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> tr = Trace(np.arange(4.0), np.ones((4, 1)), np.c_[[0.0, 1.0, 1.9, 3.71]], ("u",), ("y",))
        >>> np.round(Detector(g, ThresholdEvaluator(thresholds=[0.5])).residuals(tr).r[:, 0], 6).tolist()
        [0.0, 0.0, 0.0, 1.0]
        """
        res = self.generator.run(trace, residual_cov=self.residual_cov, recovery_tol=self.recovery_tol)
        res = res if self._index is None else res.select(self.residual_names)
        n = self.warmup_samples(trace.dt if len(trace) > 1 else self.generator.dt)
        if n:
            valid = res.valid.copy()
            valid[:n] = False
            res = replace(res, valid=valid)
        return res

    def warmup_samples(self, dt: float | None) -> int:
        """The number of samples ``warmup`` covers at sample time ``dt`` (``ceil(warmup / dt)``; 0 without one).

        Parameters
        ----------
        dt : float or None
            Sample time [s].

        Returns
        -------
        int

        Examples
        --------
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=0.1)
        >>> Detector(g, ThresholdEvaluator(thresholds=[0.5]), warmup=1.0).warmup_samples(0.1)
        10
        """
        if not self.warmup or dt is None:
            return 0
        return int(np.ceil(self.warmup / dt - 1e-9))

    def run(self, trace):
        """Decisions for a whole trace: the generator's residuals through the evaluator's ``run``.

        Parameters
        ----------
        trace : Trace
            Absolute signals, holding every control and output the detector reads.

        Returns
        -------
        Diagnosis
            One decision per sample (identical to stepping :meth:`online` through the trace).

        Raises
        ------
        DataError
            On a missing signal, a sample time other than a discrete generator's, or residuals the evaluator
            refuses.

        Examples
        --------
        >>> import numpy as np
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> from fdikit.trace import Trace
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> tr = Trace(np.arange(4.0), np.ones((4, 1)), np.c_[[0.0, 1.0, 1.9, 3.71]], ("u",), ("y",))
        >>> Detector(g, ThresholdEvaluator(thresholds=[0.5])).run(tr).alarm.tolist()
        [False, False, False, True]
        """
        return self.evaluator.run(self.residuals(trace))

    # ------------------------------------------------------------------ online
    def online(self, dt: float | None = None):
        """A stepper for sample-by-sample deployment (its own copy of the evaluator, reset).

        Parameters
        ----------
        dt : float, optional
            Sample time; needed only for a continuous generator (ZOH-discretised at ``dt``).

        Returns
        -------
        DetectorStepper
            :class:`fdikit.detector_online.DetectorStepper`.

        Raises
        ------
        ModelError
            For a continuous generator without ``dt``.
        DataError
            For a ``dt`` other than a discrete generator's own.

        Examples
        --------
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> s = Detector(g, ThresholdEvaluator(thresholds=[0.5])).online()
        >>> d = s.step({"u": 1.0}, {"y": float("nan")})
        >>> d.alarm, d.valid, s.invalid
        (False, False, 1)
        """
        from fdikit.detector_online import DetectorStepper

        return DetectorStepper(self, dt)

    # ------------------------------------------------------------------ logs and files
    def read_log(self, path: str | os.PathLike, **options):
        """Read a CSV log the way this detector was set up to: its columns, units and time column.

        Parameters
        ----------
        path : str or PathLike
            The CSV log.
        **options
            Further arguments of :meth:`fdikit.trace.Trace.from_csv` (e.g. ``dt=``, ``valid=``).

        Returns
        -------
        Trace
            The signals the detector reads, converted to SI.

        Raises
        ------
        DataError
            When the log lacks a column or a unit is unknown (from the importer), or the importer is missing.

        Examples
        --------
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> det = Detector(g, ThresholdEvaluator(thresholds=[0.5]), columns={"y": "Y"}, time_column="time")
        >>> sorted(det.log_spec())
        ['controls', 'outputs', 'time', 'units']
        """
        from fdikit.trace import Trace

        reader = getattr(Trace, "from_csv", None)
        if reader is None:
            raise DataError("this fdikit has no Trace.from_csv (fdikit.trace_import); read the log with "
                            "Trace.from_pandas and detector.log_spec()")
        return reader(path, **{**self.log_spec(), **options})

    def log_spec(self) -> dict:
        """The importer arguments that re-read a log as this detector expects (:meth:`read_log`).

        Returns
        -------
        dict
            ``time``, ``controls`` and ``outputs`` (signal -> column) and ``units`` (signal -> unit); ``time`` is
            left out when no time column was set.

        Examples
        --------
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> Detector(g, ThresholdEvaluator(thresholds=[0.5]), units={"y": "deg"}).log_spec()
        {'controls': {'u': 'u'}, 'outputs': {'y': 'y'}, 'units': {'y': 'deg'}}
        """
        spec = {"controls": {s: self.columns.get(s, s) for s in self.controls},
                "outputs": {s: self.columns.get(s, s) for s in self.outputs},
                "units": dict(self.units)}
        if self.time_column is not None:
            spec = {"time": self.time_column, **spec}
        return spec

    def with_log(self, trace) -> Detector:
        """A copy that reads logs the way ``trace`` was imported: its columns, units and time column.

        Parameters
        ----------
        trace : Trace or mapping
            A trace read by ``Trace.from_csv`` / ``Trace.from_pandas`` (or its ``meta``); only the signals the
            detector reads are taken.

        Returns
        -------
        Detector
            The same generator, evaluator and metadata with ``units``, ``columns`` and ``time_column`` replaced.

        Raises
        ------
        DataError
            When ``trace`` holds no import record.

        Examples
        --------
        >>> import pandas as pd
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> from fdikit.trace import Trace
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> df = pd.DataFrame({"time": [0.0, 1.0], "U": [1.0, 1.0], "Y": [0.0, 57.3]})
        >>> log = Trace.from_pandas(df, time="time", controls={"u": "U"}, outputs={"y": "Y"}, units={"y": "deg"})
        >>> Detector(g, ThresholdEvaluator(thresholds=[0.5])).with_log(log).log_spec()
        {'time': 'time', 'controls': {'u': 'U'}, 'outputs': {'y': 'Y'}, 'units': {'y': 'deg'}}
        """
        import dataclasses

        from fdikit.trace_import import import_arguments

        args = import_arguments(getattr(trace, "meta", trace))
        signals = self.controls + self.outputs
        columns = {**args["controls"], **args["outputs"]}
        return dataclasses.replace(
            self, units={s: u for s, u in args["units"].items() if s in signals},
            columns={s: c for s, c in columns.items() if s in signals and c != s}, time_column=args["time"])

    def save(self, path: str | os.PathLike, *, key: str | bytes | None = None) -> Path:
        """Write the detector file (:func:`fdikit.detector_file.save_detector`; atomic, digest-checked).

        Parameters
        ----------
        path : str or PathLike
            Destination file.
        key : str or bytes, optional
            HMAC secret (the file then loads only with it).

        Returns
        -------
        pathlib.Path
            The path written.

        Raises
        ------
        DataError
            When an attribute of the evaluator cannot be stored (named), or the file cannot be written.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> p = Detector(g, ThresholdEvaluator(thresholds=[0.5])).save(pathlib.Path(tempfile.mkdtemp()) / "d.json")
        >>> Detector.load(p).outputs
        ('y',)
        """
        from fdikit.detector_file import save_detector

        return save_detector(self, path, key=key)

    @classmethod
    def load(cls, path: str | os.PathLike, *, key: str | bytes | None = None) -> Detector:
        """Read a detector file (:func:`fdikit.detector_file.load_detector`): data only, never code.

        Parameters
        ----------
        path : str or PathLike
            The detector file.
        key : str or bytes, optional
            The HMAC secret it was saved with.

        Returns
        -------
        Detector

        Raises
        ------
        DataError
            For a truncated, modified, unknown-version or otherwise refused file (the message says which).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from fdikit.decision import ThresholdEvaluator
        >>> from fdikit.residuals import ResidualGenerator
        >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
        >>> p = Detector(g, ThresholdEvaluator(thresholds=[0.5]), name="n").save(pathlib.Path(tempfile.mkdtemp()) / "d")
        >>> Detector.load(p).name
        'n'
        """
        from fdikit.detector_file import load_detector

        return load_detector(path, key=key)

    def __repr__(self) -> str:
        return (f"Detector({self.name!r}: {type(self.evaluator).__name__} on {len(self.generator.residuals)} residuals "
                f"of {list(self.controls)} + {list(self.outputs)}, fdikit {self.fdikit_version}, {self.created})")
