"""Detector files: a designed detector saved as versioned, digest-checked JSON — data only, never code.

A file written by :func:`save_detector` is one JSON object in canonical form (keys sorted, one-space
indent, ASCII, no NaN literals, a final newline)::

    {
     "digest": {"algorithm": "sha256", "value": "<64 hex digits>"},
     "format": "fdikit-detector",
     "payload": {...},
     "version": 1
    }

``digest`` is the SHA-256 (or, with ``key=``, the HMAC-SHA256) of the compact canonical JSON of
``{"format", "payload", "version"}``.  :func:`load_detector` refuses (:class:`~fdikit.errors.DataError`)
a file that is not complete JSON (truncated), whose format version it does not read (naming the
version found and those supported), whose digest does not match (a changed byte), or whose text is not
the canonical form of its content (an edit that kept the content, e.g. of white space).  A plain digest
only detects accidental damage and naive edits — anyone can recompute it after a deliberate edit; when
authenticity matters save and load with a secret ``key=`` (HMAC-SHA256).

Loading never executes code from the file: no pickle, no ``eval``.  Values are JSON numbers, strings,
booleans, null and lists, plus tagged objects ``{"$": tag, ...}``: ``tuple``, ``dict`` (ordered key/value
pairs), ``ndarray`` (dtype, shape and base64 of the little-endian bytes: arrays are stored bit for bit),
``scalar`` (a numpy scalar, likewise), ``set``/``frozenset`` (items in canonical order), ``float`` (a
non-finite float), ``rng`` (a numpy Generator's bit-generator state) and ``object``: an instance of a
class on the explicit allowlist :data:`REGISTRY`, rebuilt from its stored attributes without calling its
constructor.  An evaluator (a registry class with ``reset``) is stored without the attributes its
``reset()`` reassigns (its per-run state, found generically by resetting a copy) and is ``reset()``
after loading; any other attribute of a type outside the list above is refused on saving with a
DataError naming the evaluator and the attribute.  The format is documented in
``docs/methods/deployment.md``.

Examples
--------
>>> import tempfile, pathlib
>>> from fdikit.decision import ThresholdEvaluator
>>> from fdikit.detector import Detector
>>> from fdikit.residuals import ResidualGenerator
>>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
>>> det = Detector(g, ThresholdEvaluator(thresholds=[0.5]), name="demo")
>>> path = save_detector(det, pathlib.Path(tempfile.mkdtemp()) / "demo.json")
>>> back = load_detector(path)
>>> back.name, back.evaluator.thresholds.tolist(), bool((back.generator.B == g.B).all())
('demo', [0.5], True)
"""

from __future__ import annotations

import base64
import copy
import hashlib
import hmac
import importlib
import inspect
import json
import math
import os
from pathlib import Path

import numpy as np

from fdikit.errors import DataError, ParameterError

__all__ = ["FORMAT", "REGISTRY", "SUPPORTED_VERSIONS", "VERSION", "load_detector", "save_detector"]

#: The ``format`` field of every detector file.
FORMAT = "fdikit-detector"
#: The format version :func:`save_detector` writes.
VERSION = 1
#: The format versions :func:`load_detector` reads.
SUPPORTED_VERSIONS = (1,)

#: The classes a detector file may hold: registry name -> ``"module:attribute"``.  Nothing else is rebuilt.
REGISTRY = {
    "ResidualGenerator": "fdikit.residuals.generator:ResidualGenerator",
    "OperatingPoint": "fdikit.operating_point:OperatingPoint",
    "ThresholdEvaluator": "fdikit.decision.threshold:ThresholdEvaluator",
    "CusumEvaluator": "fdikit.decision.cusum:CusumEvaluator",
    "GlrEvaluator": "fdikit.decision.glr:GlrEvaluator",
    "SprtEvaluator": "fdikit.decision.sprt:SprtEvaluator",
    "MhsprtEvaluator": "fdikit.decision.mhsprt:MhsprtEvaluator",
    "GaussianDensity": "fdikit.decision.densities:GaussianDensity",
    "UniformMeanDensity": "fdikit.decision.densities:UniformMeanDensity",
    "Whitened": "fdikit.decision.whiten:Whitened",
    "GaussianMlEvaluator": "fdikit.decision.learned.gaussian_ml:GaussianMlEvaluator",
    "BnnEvaluator": "fdikit.decision.learned.bnn:BnnEvaluator",
    "BnnNetwork": "fdikit.decision.learned.network:BnnNetwork",
    "TrainingReport": "fdikit.decision.learned.bnn:TrainingReport",
    "LabelledInputs": "fdikit.decision.learned.labelled_runs:LabelledInputs",
    "SignatureTable": "fdikit.decision.signature:SignatureTable",
    "CalibrationReport": "fdikit.decision.calibration:CalibrationReport",
}

#: numpy bit generators whose state a file may hold (``rng`` values).
_BIT_GENERATORS = ("PCG64", "PCG64DXSM", "MT19937", "Philox", "SFC64")
_ARRAY_KINDS = "biufcU"
_MAX_DEPTH = 64


def _registry_class(name: str, where: str):
    spec = REGISTRY.get(name) if isinstance(name, str) else None
    if spec is None:
        raise DataError(f"{where}: class {name!r} is not on the allowlist of classes a detector file may hold "
                        f"({sorted(REGISTRY)}); the file is refused (nothing outside the list is ever rebuilt)")
    module, attr = spec.split(":")
    return getattr(importlib.import_module(module), attr)


def _registry_name(obj) -> str | None:
    cls = type(obj)
    for name, spec in REGISTRY.items():
        module, attr = spec.split(":")
        if cls.__name__ == attr and cls.__module__ == module:
            return name
    return None


# ---------------------------------------------------------------------------------------------- encoding
def _array_node(tag: str, arr: np.ndarray, where: str) -> dict:
    if arr.dtype.kind not in _ARRAY_KINDS or arr.dtype.fields is not None:
        raise DataError(f"{where}: an array of dtype {arr.dtype} cannot be stored in a detector file; "
                        "only boolean, integer, float, complex and unicode arrays can")
    dt = arr.dtype.newbyteorder("<")
    data = np.ascontiguousarray(arr, dtype=dt).tobytes()
    node = {"$": tag, "dtype": dt.str, "data": base64.b64encode(data).decode("ascii")}
    if tag == "ndarray":
        node["shape"] = list(arr.shape)
        if not arr.flags.writeable:
            node["readonly"] = True
    return node


def _fields(obj, where: str) -> dict:
    """The attributes stored for ``obj``: all, less those its ``reset()`` reassigns (per-run state)."""
    try:
        attrs = dict(vars(obj))
    except TypeError:
        raise DataError(f"{where}: a {type(obj).__name__} has no attribute dictionary; it cannot be stored") from None
    reset = getattr(type(obj), "reset", None)
    if callable(reset):
        twin = copy.deepcopy(obj)
        before = dict(vars(twin))
        twin.reset()
        after = vars(twin)
        per_run = {k for k, v in after.items() if k not in before or before[k] is not v}
        attrs = {k: v for k, v in attrs.items() if k not in per_run and k in after}  # the originals, not copies
    return attrs


def _encode(value, where: str, depth: int = 0):
    if depth > _MAX_DEPTH:
        raise DataError(f"{where}: nested more than {_MAX_DEPTH} levels deep; cannot be stored")
    if value is None or isinstance(value, (bool, str)) and type(value) in (bool, str):
        return value
    if type(value) is int:
        return value
    if type(value) is float:
        return value if math.isfinite(value) else {"$": "float", "value": repr(value)}
    if type(value) is np.ndarray:
        return _array_node("ndarray", value, where)
    if isinstance(value, np.generic) and type(value) is not np.object_:
        return _array_node("scalar", np.asarray(value), where)
    if type(value) is list:
        return [_encode(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value)]
    if type(value) is tuple:
        return {"$": "tuple", "items": [_encode(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value)]}
    if type(value) in (set, frozenset):
        items = [_encode(v, f"{where} item", depth + 1) for v in value]
        return {"$": type(value).__name__, "items": sorted(items, key=_canonical)}
    if type(value) is dict:
        return {"$": "dict", "items": [[_encode(k, f"{where} key {k!r}", depth + 1),
                                        _encode(v, f"{where}[{k!r}]", depth + 1)] for k, v in value.items()]}
    if type(value) is np.random.Generator:
        state = value.bit_generator.state
        if state.get("bit_generator") not in _BIT_GENERATORS:
            raise DataError(f"{where}: a random generator on {state.get('bit_generator')!r} cannot be stored; "
                            f"use one of {list(_BIT_GENERATORS)}")
        return {"$": "rng", "state": _encode(state, f"{where}.state", depth + 1)}
    name = _registry_name(value)
    if name is None:
        raise DataError(f"{where} is a {type(value).__module__}.{type(value).__qualname__}, a type a detector file "
                        "cannot hold (numbers, strings, booleans, None, lists, tuples, dicts, numpy arrays and "
                        f"scalars, numpy Generators and the fdikit classes {sorted(REGISTRY)}); set it to one of "
                        "these or leave it out of the evaluator before saving")
    fields = _fields(value, where)
    return {"$": "object", "class": name,
            "fields": {k: _encode(v, f"{where}.{k}", depth + 1) for k, v in fields.items()}}


# ---------------------------------------------------------------------------------------------- decoding
def _array(node: dict, where: str) -> np.ndarray:
    try:
        dt = np.dtype(node["dtype"])
        raw = base64.b64decode(node["data"].encode("ascii"), validate=True)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise DataError(f"{where}: a malformed array ({exc})") from None
    if dt.kind not in _ARRAY_KINDS or dt.fields is not None or dt.byteorder == ">":
        raise DataError(f"{where}: array dtype {dt} is not allowed in a detector file")
    shape = node.get("shape", [])
    if not (isinstance(shape, list) and all(type(s) is int and s >= 0 for s in shape)):
        raise DataError(f"{where}: a malformed array shape {shape!r}")
    if len(raw) != math.prod(shape) * dt.itemsize:
        raise DataError(f"{where}: {len(raw)} bytes for an array of shape {shape} and dtype {dt}")
    return np.frombuffer(raw, dtype=dt).reshape(shape).astype(dt.newbyteorder("="), copy=True)


def _check_field(cls, name, where: str) -> None:
    """Refuse an attribute name that is not an identifier or would shadow a method or property of ``cls``."""
    if not isinstance(name, str) or not name.isidentifier() or name.startswith("__"):
        raise DataError(f"{where}: {name!r} is not an attribute name a detector file may set")
    static = inspect.getattr_static(cls, name, None)
    if callable(static) or isinstance(static, (property, classmethod, staticmethod)):
        raise DataError(f"{where}: attribute {name!r} would replace a method or property of {cls.__name__}")


def _decode(node, where: str, depth: int = 0):
    if depth > _MAX_DEPTH:
        raise DataError(f"{where}: nested more than {_MAX_DEPTH} levels deep")
    if node is None or type(node) in (bool, str, int, float):
        return node
    if type(node) is list:
        return [_decode(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(node)]
    if type(node) is not dict:
        raise DataError(f"{where}: unexpected JSON value {node!r}")
    tag = node.get("$")
    if tag == "tuple":
        return tuple(_decode(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(node["items"]))
    if tag in ("set", "frozenset"):
        try:
            items = [_decode(v, f"{where} item", depth + 1) for v in node["items"]]
            return set(items) if tag == "set" else frozenset(items)
        except TypeError:
            raise DataError(f"{where}: a set item is not hashable") from None
    if tag == "dict":
        out = {}
        for i, pair in enumerate(node["items"]):
            if type(pair) is not list or len(pair) != 2:
                raise DataError(f"{where}: item {i} is not a [key, value] pair")
            key = _decode(pair[0], f"{where} key {i}", depth + 1)
            try:
                out[key] = _decode(pair[1], f"{where}[{key!r}]", depth + 1)
            except TypeError:
                raise DataError(f"{where}: key {key!r} is not hashable") from None
        return out
    if tag == "float":
        if node.get("value") not in ("nan", "inf", "-inf"):
            raise DataError(f"{where}: a non-finite float must be 'nan', 'inf' or '-inf', got {node.get('value')!r}")
        return float(node["value"])
    if tag == "ndarray":
        arr = _array(node, where)
        if node.get("readonly"):
            arr.setflags(write=False)
        return arr
    if tag == "scalar":
        return _array(node, where).reshape(-1)[0]
    if tag == "rng":
        state = _decode(node["state"], f"{where}.state", depth + 1)
        name = state.get("bit_generator") if isinstance(state, dict) else None
        if name not in _BIT_GENERATORS:
            raise DataError(f"{where}: bit generator {name!r} is not one of {list(_BIT_GENERATORS)}")
        bits = getattr(np.random, name)()
        try:
            bits.state = state
        except (TypeError, ValueError, KeyError) as exc:
            raise DataError(f"{where}: a malformed {name} state ({exc})") from None
        return np.random.Generator(bits)
    if tag == "object":
        cls = _registry_class(node.get("class"), where)
        fields = node.get("fields")
        if type(fields) is not dict:
            raise DataError(f"{where}: an object without a 'fields' mapping")
        for k in fields:
            _check_field(cls, k, where)
        obj = cls.__new__(cls)
        obj.__dict__.update({k: _decode(v, f"{where}.{k}", depth + 1) for k, v in fields.items()})
        if callable(getattr(cls, "reset", None)):
            obj.reset()
        return obj
    raise DataError(f"{where}: unknown value tag {tag!r}")


# ---------------------------------------------------------------------------------------------- the file
def _canonical(doc) -> bytes:
    return json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False).encode("ascii")


def _file_text(doc: dict) -> str:
    return json.dumps(doc, sort_keys=True, indent=1, ensure_ascii=True, allow_nan=False) + "\n"


def _key_bytes(key) -> bytes | None:
    if key is None:
        return None
    if isinstance(key, str):
        key = key.encode("utf-8")
    if not isinstance(key, (bytes, bytearray)) or not key:
        raise ParameterError(f"key must be a non-empty str or bytes (the HMAC secret), got {type(key).__name__}")
    return bytes(key)


def _digest(body: dict, key: bytes | None) -> dict:
    msg = _canonical(body)
    if key is None:
        return {"algorithm": "sha256", "value": hashlib.sha256(msg).hexdigest()}
    return {"algorithm": "hmac-sha256", "value": hmac.new(key, msg, hashlib.sha256).hexdigest()}


def _payload(detector) -> dict:
    op = detector.operating_point
    return {
        "detector": {"name": detector.name, "description": detector.description, "created": detector.created,
                     "fdikit_version": detector.fdikit_version},
        "signals": {"controls": list(detector.controls), "outputs": list(detector.outputs),
                    "residuals": list(detector.generator.residuals)},
        "operating_point": None if op is None else op.as_dict(),
        "log": {"units": dict(detector.units), "columns": dict(detector.columns), "time": detector.time_column},
        "options": {"recovery_tol": _encode(detector.recovery_tol, "recovery_tol"),
                    "residual_cov": _encode(detector.residual_cov, "residual_cov"),
                    "warmup": _encode(detector.warmup, "warmup")},
        "generator": _encode(detector.generator, "the generator"),
        "evaluator": _encode(detector.evaluator, f"the evaluator {type(detector.evaluator).__name__}"),
    }


def save_detector(detector, path: str | os.PathLike, *, key: str | bytes | None = None) -> Path:
    """Write ``detector`` to ``path`` (atomically) in the detector file format.

    Parameters
    ----------
    detector : fdikit.detector.Detector
        The detector to save.
    path : str or PathLike
        Destination file (``.json`` recommended); its folder is created when missing.
    key : str or bytes, optional
        A secret for an HMAC-SHA256 digest instead of a plain SHA-256 one; the file then loads only with
        the same key.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    DataError
        When the evaluator (or the generator) holds an attribute of a type a file cannot hold (the message
        names the evaluator and the attribute), or the file cannot be written.
    ParameterError
        When ``detector`` is not a Detector or ``key`` is not a non-empty str or bytes.

    Examples
    --------
    >>> import tempfile, pathlib, json
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.detector import Detector
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> det = Detector(g, ThresholdEvaluator(thresholds=[0.5]))
    >>> p = save_detector(det, pathlib.Path(tempfile.mkdtemp()) / "d.json")
    >>> doc = json.loads(p.read_text())
    >>> doc["format"], doc["version"], doc["digest"]["algorithm"]
    ('fdikit-detector', 1, 'sha256')
    """
    from fdikit.atomic import write_text
    from fdikit.detector import Detector

    if not isinstance(detector, Detector):
        raise ParameterError(f"save_detector needs a fdikit.detector.Detector, got {type(detector).__name__}")
    secret = _key_bytes(key)
    body = {"format": FORMAT, "version": VERSION, "payload": _payload(detector)}
    doc = {**body, "digest": _digest(body, secret)}
    return write_text(path, _file_text(doc), encoding="ascii")


def _document(text: str, where: str) -> dict:
    def no_constants(name):
        raise ValueError(f"the non-JSON constant {name}")

    def pairs(items):
        keys = [k for k, _ in items]
        if len(set(keys)) != len(keys):
            raise ValueError(f"a repeated key among {keys}")
        return dict(items)

    try:
        doc = json.loads(text, parse_constant=no_constants, object_pairs_hook=pairs)
    except (ValueError, RecursionError) as exc:
        raise DataError(f"{where} is not a complete detector file: it is truncated or damaged ({exc}); "
                        "re-save the detector from its source") from None
    if type(doc) is not dict or doc.get("format") != FORMAT:
        raise DataError(f"{where} is not a fdikit detector file (no \"format\": {FORMAT!r} at the top level)")
    return doc


def load_detector(path: str | os.PathLike, *, key: str | bytes | None = None):
    """Read a detector written by :func:`save_detector`; refuse any file that is not exactly what was written.

    Parameters
    ----------
    path : str or PathLike
        The detector file.
    key : str or bytes, optional
        The HMAC secret the file was saved with; required for, and only accepted with, an HMAC-signed file.

    Returns
    -------
    fdikit.detector.Detector
        The detector, its arrays bit-identical to the saved ones and its evaluator reset.

    Raises
    ------
    DataError
        When the file cannot be read, is truncated or not JSON, is not a detector file, has a format version
        this fdikit does not read (naming the version found and the versions supported), has a digest that
        does not match its content (modified or damaged), is not in canonical form, lacks the key it was
        signed with, or names a class outside :data:`REGISTRY`.
    ParameterError
        When ``key`` is not a non-empty str or bytes.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from fdikit.decision import ThresholdEvaluator
    >>> from fdikit.detector import Detector
    >>> from fdikit.residuals import ResidualGenerator
    >>> g = ResidualGenerator([[0.4]], [[1.0, 0.5]], [[-1.0]], [[0.0, 1.0]], ("u",), ("y",), ("r",), dt=1.0)
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "d.json"
    >>> _ = save_detector(Detector(g, ThresholdEvaluator(thresholds=[0.5])), p, key="secret")
    >>> load_detector(p, key="secret").controls
    ('u',)
    >>> try:
    ...     load_detector(p)
    ... except DataError as exc:
    ...     print("refused")
    refused
    """
    secret = _key_bytes(key)
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise DataError(f"cannot read the detector file {path}: {exc.strerror or exc}") from None
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path} is not a detector file or is damaged: byte {exc.start} is not ASCII") from None
    doc = _document(text, str(path))
    version = doc.get("version")
    if type(version) is not int or version not in SUPPORTED_VERSIONS:
        raise DataError(f"{path} has detector file format version {version!r}; this fdikit reads versions "
                        f"{list(SUPPORTED_VERSIONS)}: use the fdikit that wrote it, or re-save the detector "
                        "with this one")
    if set(doc) != {"format", "version", "digest", "payload"}:
        raise DataError(f"{path}: top-level fields {sorted(doc)}; a version-{version} detector file has exactly "
                        "digest, format, payload and version")
    digest = doc["digest"]
    algorithm = digest.get("algorithm") if type(digest) is dict else None
    if algorithm not in ("sha256", "hmac-sha256") or type(digest.get("value")) is not str:
        raise DataError(f"{path}: a malformed digest {digest!r}; expected an algorithm 'sha256' or 'hmac-sha256' "
                        "and a hex value")
    if algorithm == "hmac-sha256" and secret is None:
        raise DataError(f"{path} is signed with HMAC-SHA256; pass key= (the secret it was saved with) to load it")
    if algorithm == "sha256" and secret is not None:
        raise DataError(f"{path} carries only a plain SHA-256 digest, not an HMAC signature: its authenticity "
                        "cannot be checked with key=; re-save it with key= or load it without a key")
    body = {k: doc[k] for k in ("format", "version", "payload")}
    if not hmac.compare_digest(_digest(body, secret)["value"], digest["value"]):
        what = "the key is wrong or the file" if secret is not None else "the file"
        raise DataError(f"{path}: the {algorithm} digest does not match the content — {what} was modified or damaged "
                        "after it was written (tampered or truncated); refusing to load it")
    if text != _file_text(doc):
        raise DataError(f"{path} is not in the canonical form save_detector writes: it was edited after writing; "
                        "refusing to load it")
    return _detector(doc["payload"], str(path))


def _detector(payload: dict, where: str):
    from fdikit.detector import Detector

    try:
        meta, log, options = payload["detector"], payload["log"], payload["options"]
        det = Detector(
            _decode(payload["generator"], f"{where}: generator"),
            _decode(payload["evaluator"], f"{where}: evaluator"),
            units=log["units"], columns=log["columns"], time_column=log["time"],
            name=meta["name"], description=meta["description"], created=meta["created"],
            fdikit_version=meta["fdikit_version"],
            residual_cov=_decode(options["residual_cov"], f"{where}: residual_cov"),
            recovery_tol=_decode(options["recovery_tol"], f"{where}: recovery_tol"),
            warmup=_decode(options.get("warmup", 0.0), f"{where}: warmup"),   # absent in files before it existed
        )
    except (KeyError, TypeError, AttributeError, ValueError, IndexError) as exc:
        if isinstance(exc, DataError):
            raise
        raise DataError(f"{where}: the payload lacks or misshapes a field ({exc!r})") from None
    signals = {"controls": list(det.controls), "outputs": list(det.outputs), "residuals": list(det.generator.residuals)}
    op = det.operating_point
    if payload.get("signals") != signals or payload.get("operating_point") != (None if op is None else op.as_dict()):
        raise DataError(f"{where}: the signals or operating point listed do not match the stored generator")
    return det
