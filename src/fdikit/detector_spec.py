"""A detector from a design spec: a model, its filters, how its logs read, how it is calibrated.

What ``fdikit design`` builds (``docs/tutorial.md``).  A spec is a YAML file or a Python module (a
``.py`` file or an importable module name) with these entries — in YAML as keys, in Python as module
attributes of the same names (``model`` may there be a :class:`~fdikit.model.FaultModel` or a function
returning one, e.g. after :func:`~fdikit.nonlinear.trim_and_linearize`):

``name``, ``description``
    Metadata of the detector.
``model``
    The LTI model in deviation coordinates.  YAML: ``A``, ``B``, ``C``, ``D`` (optional), ``dt`` (optional;
    omitted means continuous, discretised at the calibration logs' sample time), ``states``, ``controls``,
    ``outputs`` and ``operating_point`` (``{x0: {...}, u0: {...}, y0: {...}}``, absolute values by name).
``sensor_faults``, ``actuator_faults``
    Outputs and controls whose sensor / actuator faults the detector isolates (default every one, unless
    the model already has fault inputs).
``filters``
    The bank: a list of ``{name, outputs, process_noise_cov, measurement_noise_std}`` — each a steady-state
    Kalman filter (:func:`fdikit.design.kalman`) reading the controls and the listed outputs (default all),
    ``process_noise_cov`` the ``Q`` of the model's noise inputs (or of noise on every state), per sample;
    default one filter reading every output.  Filters reading different sensors make the bank's fault
    signatures differ: the isolation logic is the signature table of the bank on the model
    (:meth:`fdikit.decision.SignatureTable.from_generator`), so a fault that fires several filters is named
    when its whole pattern fired.
``log``
    ``{time, columns: {signal: column}, units: {signal: unit}}``: how the logs are read
    (:meth:`fdikit.trace.Trace.from_csv`).
``calibration``
    ``{false_alarms_per_hour, persistence: [k, n], match, warmup}``: thresholds set on the fault-free logs given
    to :func:`build_detector` (a list of runs: :meth:`fdikit.decision.ThresholdEvaluator.fit`); ``warmup``
    seconds at the start of every run are left out of the calibration and of the decisions
    (:class:`~fdikit.detector.Detector`).

The spec is checked by pydantic (the field names above, their types); a Python spec is user code and is
executed when loaded — only the detector *files* (:mod:`fdikit.detector_file`) are data only.

Examples
--------
>>> spec = DesignSpec.model_validate({"model": {"A": [[0.9]], "B": [[1.0]], "C": [[1.0]], "dt": 0.1,
...                                   "controls": ["u"], "outputs": ["y"]}})
>>> spec.filters[0].name, spec.calibration.false_alarms_per_hour
('kalman', 1.0)
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from fdikit.errors import DataError, ParameterError

__all__ = ["CalibrationSpec", "DesignSpec", "FilterSpec", "LogSpec", "ModelSpec", "build_detector", "load_spec",
           "read_logs"]

_STRICT = ConfigDict(extra="forbid", arbitrary_types_allowed=True)


class ModelSpec(BaseModel):
    """The LTI model of a YAML spec (deviation coordinates; see the module docstring).

    Examples
    --------
    >>> ModelSpec(A=[[0.9]], B=[[1.0]], C=[[1.0]], dt=0.1, operating_point={"y0": {"y0": 2.0}}).dt
    0.1
    """

    model_config = _STRICT
    A: list[list[float]]
    B: list[list[float]] | None = None
    C: list[list[float]]
    D: list[list[float]] | None = None
    dt: float | None = Field(default=None, gt=0)
    states: list[str] | None = None
    controls: list[str] | None = None
    outputs: list[str] | None = None
    operating_point: dict[str, dict[str, float]] | None = None

    def build(self):
        """The :class:`~fdikit.model.FaultModel` (with its operating point).

        Returns
        -------
        FaultModel

        Raises
        ------
        ModelError, ParameterError
            For matrices of inconsistent shapes or a bad operating point.

        Examples
        --------
        >>> ModelSpec(A=[[0.5]], C=[[1.0]], dt=1.0).build()
        FaultModel(discrete dt=1, n=1, p=1, u=0, d=0, f=0, w=0)
        """
        from fdikit.model import FaultModel
        from fdikit.operating_point import OperatingPoint

        op = None if self.operating_point is None else OperatingPoint.from_dict(self.operating_point)
        return FaultModel(A=self.A, C=self.C, Bu=self.B, Du=self.D, states=self.states, controls=self.controls,
                          outputs=self.outputs, dt=self.dt, operating_point=op)


class FilterSpec(BaseModel):
    """One Kalman filter of the bank: its name, the outputs it reads and its noise covariances.

    Examples
    --------
    >>> FilterSpec(name="yaw", outputs=["yaw_rate"], measurement_noise_std=0.002).process_noise_cov
    1e-06
    """

    model_config = _STRICT
    name: str = Field(min_length=1, pattern=r"^[^:]+$")
    outputs: list[str] | None = None
    process_noise_cov: float | list[float] | list[list[float]] = 1e-6
    measurement_noise_std: float | list[float] = 1e-3


class LogSpec(BaseModel):
    """How a log reads: its time column, the column of each signal and each signal's unit.

    Examples
    --------
    >>> LogSpec(time="time", units={"yaw_rate": "deg/s"}).units
    {'yaw_rate': 'deg/s'}
    """

    model_config = _STRICT
    time: str | None = None
    columns: dict[str, str] = Field(default_factory=dict)
    units: dict[str, str] = Field(default_factory=dict)


class CalibrationSpec(BaseModel):
    """The false-alarm target, the persistence and the signature match rule of the thresholds.

    Examples
    --------
    >>> CalibrationSpec(persistence=(3, 5)).false_alarms_per_hour
    1.0
    """

    model_config = _STRICT
    false_alarms_per_hour: float = Field(default=1.0, gt=0)
    persistence: tuple[int, int] = (1, 1)
    match: str = "exact"
    warmup: float = Field(default=0.0, ge=0)


class DesignSpec(BaseModel):
    """A whole design spec (module docstring); ``model`` is a :class:`ModelSpec` or a FaultModel.

    Examples
    --------
    >>> DesignSpec(model={"A": [[0.9]], "C": [[1.0]], "dt": 0.1}, name="demo").filters[0].outputs is None
    True
    """

    model_config = _STRICT
    name: str = "detector"
    description: str = ""
    model: Any
    sensor_faults: list[str] | None = None
    actuator_faults: list[str] | None = None
    filters: list[FilterSpec] = Field(default_factory=lambda: [FilterSpec(name="kalman")])
    log: LogSpec = Field(default_factory=LogSpec)
    calibration: CalibrationSpec = Field(default_factory=CalibrationSpec)

    @field_validator("model", mode="before")
    @classmethod
    def _matrices(cls, value):
        """A mapping of matrices is a :class:`ModelSpec` (checked when the spec is read, not at design time)."""
        return ModelSpec.model_validate(value) if isinstance(value, dict) else value

    def base_model(self):
        """The spec's model as given: a :class:`~fdikit.model.FaultModel`, no faults added, not discretised.

        Returns
        -------
        FaultModel

        Raises
        ------
        ParameterError
            When ``model`` is neither a FaultModel, a function returning one, nor a mapping of matrices.

        Examples
        --------
        >>> DesignSpec(model={"A": [[-1.0]], "C": [[1.0]]}).base_model().is_discrete
        False
        """
        from fdikit.model import FaultModel

        m = self.model() if callable(self.model) and not isinstance(self.model, FaultModel) else self.model
        if isinstance(m, ModelSpec):
            m = m.build()
        if not isinstance(m, FaultModel):
            raise ParameterError(f"the spec's model must be a FaultModel, a function returning one or a mapping "
                                 f"of matrices, got {type(m).__name__}")
        return m

    def fault_model(self, dt: float | None = None):
        """The model (discretised at ``dt`` when it is continuous) with the spec's fault inputs.

        Parameters
        ----------
        dt : float, optional
            The sample time of the logs; needed for a continuous model.

        Returns
        -------
        FaultModel
            Discrete, with sensor and actuator fault inputs.

        Raises
        ------
        ParameterError
            For a continuous model without ``dt``, a discrete model at another ``dt``, or fault names
            the model does not have.

        Examples
        --------
        >>> spec = DesignSpec(model={"A": [[-1.0]], "B": [[1.0]], "C": [[1.0]], "controls": ["u"], "outputs": ["y"]})
        >>> spec.fault_model(0.1).faults
        ('y_sensor', 'u_actuator')
        """
        m = self.base_model()
        if not m.is_discrete:
            if dt is None:
                raise ParameterError("the spec's model is continuous: give dt (or calibration logs, whose sample "
                                     "time is used)")
            m = m.discretize(dt)
        elif dt is not None and not np.isclose(dt, m.dt, rtol=1e-6):
            raise ParameterError(f"the spec's model is discrete at dt={m.dt:g} s but the logs are sampled at "
                                 f"{dt:g} s; resample the logs or give a continuous model")
        if not m.faults or self.sensor_faults is not None or self.actuator_faults is not None:
            sensors = list(m.outputs) if self.sensor_faults is None else self.sensor_faults
            actuators = list(m.controls) if self.actuator_faults is None else self.actuator_faults
            if sensors:
                m = m.with_sensor_faults(sensors)
            if actuators:
                m = m.with_actuator_faults(actuators)
        return m


def _spec_error(where: str, exc: ValidationError) -> ParameterError:
    lines = [f"  {'.'.join(str(p) for p in e['loc']) or '(top)'}: {e['msg']}" for e in exc.errors()]
    return ParameterError(f"the design spec {where} is not valid:\n" + "\n".join(lines))


def load_spec(source: str | os.PathLike) -> DesignSpec:
    """Read a design spec from a YAML file, a Python file or an importable Python module.

    Parameters
    ----------
    source : str or PathLike
        ``spec.yaml`` / ``spec.yml``, ``plant.py`` (run with its folder on ``sys.path``, so it may import a
        module beside it), or a module name such as ``mypkg.car_spec``.

    Returns
    -------
    DesignSpec

    Raises
    ------
    DataError
        When the file does not exist or is not valid YAML, or the module cannot be imported.
    ParameterError
        When an entry is missing or has the wrong type (pydantic's message for each one).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "spec.yaml"
    >>> _ = p.write_text("model: {A: [[0.9]], B: [[1.0]], C: [[1.0]], dt: 0.1}\\nname: demo\\n")
    >>> load_spec(p).name
    'demo'
    """
    text = os.fspath(source)
    path = Path(text)
    if path.suffix in (".yaml", ".yml"):
        import yaml

        if not path.is_file():
            raise DataError(f"design spec {path} does not exist")
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8"))
        except yaml.YAMLError as exc:
            raise DataError(f"design spec {path} is not valid YAML: {exc}") from None
        if not isinstance(data, dict):
            raise DataError(f"design spec {path} must be a YAML mapping with a 'model' key")
    else:
        module = _import(text, path)
        data = {k: getattr(module, k) for k in DesignSpec.model_fields if hasattr(module, k)}
        if "model" not in data:
            raise ParameterError(f"the Python design spec {text} defines no 'model' (a FaultModel or a function "
                                 "returning one)")
    try:
        return DesignSpec.model_validate(data)
    except ValidationError as exc:
        raise _spec_error(text, exc) from None


def _import(text: str, path: Path):
    if path.suffix == ".py":
        if not path.is_file():
            raise DataError(f"design spec {path} does not exist")
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        folder = str(path.resolve().parent)
        sys.path.insert(0, folder)   # the spec may import the plant module beside it, as a script would
        try:
            spec.loader.exec_module(module)
        finally:
            sys.path.remove(folder)
        return module
    try:
        return importlib.import_module(text)
    except ImportError as exc:
        raise DataError(f"cannot import the design spec module {text!r} ({exc}); give a .yaml or .py file or an "
                        "importable module name") from None


def read_logs(spec: DesignSpec, paths: Sequence[str | os.PathLike], signals: Sequence[str] | None = None):
    """The logs as traces, read as the spec's ``log`` entry says.

    Parameters
    ----------
    spec : DesignSpec
        The spec.
    paths : sequence of path
        CSV logs.
    signals : (controls, outputs), optional
        The names to read; default the spec model's.

    Returns
    -------
    list of Trace

    Raises
    ------
    DataError
        As :meth:`fdikit.trace.Trace.from_csv`.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "log.csv"
    >>> _ = p.write_text("t,u,y_deg\\n0,0,0\\n0.1,1,90\\n")
    >>> spec = DesignSpec(model={"A": [[0.9]], "B": [[1.0]], "C": [[1.0]], "dt": 0.1, "controls": ["u"],
    ...                          "outputs": ["y"]}, log={"time": "t", "columns": {"y": "y_deg"}, "units": {"y": "deg"}})
    >>> read_logs(spec, [p], (["u"], ["y"]))[0].y[:, 0].round(6).tolist()
    [0.0, 1.570796]
    """
    from fdikit.trace import Trace

    if signals is None:
        base = spec.base_model()
        signals = (base.controls, base.outputs)
    controls, outputs = signals
    cols = spec.log.columns
    kw = {"controls": {s: cols.get(s, s) for s in controls}, "outputs": {s: cols.get(s, s) for s in outputs},
          "units": {s: u for s, u in spec.log.units.items() if s in (*controls, *outputs)}}
    if spec.log.time is not None:
        kw["time"] = spec.log.time
    return [Trace.from_csv(p, **kw) for p in paths]


def build_detector(spec: DesignSpec, healthy: Sequence[str | os.PathLike]):
    """Design the spec's filter bank and calibrate its thresholds on fault-free logs.

    Parameters
    ----------
    spec : DesignSpec
        From :func:`load_spec` (or built in Python).
    healthy : sequence of path
        Fault-free CSV logs (at least one; more runs give a better-known false-alarm rate: the detector's
        ``evaluator.calibration`` reports the rate the thresholds give on them and its interval).

    Returns
    -------
    Detector
        The bank (:func:`fdikit.residuals.stack_generators`), a :class:`~fdikit.decision.ThresholdEvaluator`
        with the bank's signature table, the log's units and columns, the model's operating point.

    Raises
    ------
    ParameterError
        For no logs, a filter reading an output the model does not have, or a bad noise covariance.
    DataError
        For a log that cannot be read.
    DesignError
        When a Kalman filter has no stabilising solution.

    Examples
    --------
    A first-order plant ``y⁺ = 0.9 y + 0.1 u`` logged in degrees, one fault-free log (see ``docs/tutorial.md``):

    >>> import pathlib, tempfile
    >>> import numpy as np, pandas as pd
    >>> rng = np.random.default_rng(0)
    >>> u = rng.standard_normal(3000)
    >>> y = np.zeros(3000)
    >>> for k in range(2999):
    ...     y[k + 1] = 0.9 * y[k] + 0.1 * u[k]
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "healthy.csv"
    >>> pd.DataFrame({"t": np.arange(3000) * 0.1, "u": u, "y_deg": np.rad2deg(y + 0.01 * rng.standard_normal(3000))}
    ...              ).to_csv(path, index=False)
    >>> spec = DesignSpec(model={"A": [[0.9]], "B": [[0.1]], "C": [[1.0]], "dt": 0.1, "controls": ["u"],
    ...                          "outputs": ["y"]}, filters=[{"name": "k", "measurement_noise_std": 0.01}],
    ...                   log={"time": "t", "columns": {"y": "y_deg"}, "units": {"y": "deg"}})
    >>> det = build_detector(spec, [path])
    >>> det.evaluator.names, det.evaluator.signatures.signature("y_sensor")
    (('k:y',), ('k:y',))
    """
    from fdikit.decision import SignatureTable, ThresholdEvaluator
    from fdikit.design import kalman
    from fdikit.detector import Detector
    from fdikit.residuals import stack_generators

    if isinstance(healthy, (str, os.PathLike)) or not healthy:
        raise ParameterError("build_detector needs a list of fault-free logs to calibrate the thresholds on")
    base = spec.base_model()
    traces = read_logs(spec, healthy, (base.controls, base.outputs))
    model = spec.fault_model(traces[0].dt)
    gens = []
    for f in spec.filters:
        outputs = list(model.outputs) if f.outputs is None else f.outputs
        sub = model.submodel(outputs=outputs)
        std = np.broadcast_to(np.asarray(f.measurement_noise_std, dtype=float), (len(outputs),))
        design = kalman(sub, f.process_noise_cov, np.diag(std**2), names=[f"{f.name}:{y}" for y in outputs])
        gens.append(design.generator)
    bank = stack_generators(gens)
    table = SignatureTable.from_generator(bank, model, match=spec.calibration.match)
    ev = ThresholdEvaluator(persistence=spec.calibration.persistence, signatures=table)
    signals = set(bank.controls + bank.outputs)
    det = Detector(bank, ev, units={s: u for s, u in spec.log.units.items() if s in signals},
                   columns={s: c for s, c in spec.log.columns.items() if s in signals}, time_column=spec.log.time,
                   name=spec.name, description=spec.description, warmup=spec.calibration.warmup)
    ev.fit([det.residuals(tr) for tr in traces], false_alarms_per_hour=spec.calibration.false_alarms_per_hour)
    return det
