"""fdikit.detector_file: save -> load gives identical decisions in a fresh process; damaged, edited,
unknown-version and non-allowlisted files are refused; the load path never unpickles.

The digests the tests recompute (to play a naive editor) are computed here independently, from the
format's definition in docs/methods/deployment.md, with hashlib/hmac and json — not by fdikit.
"""

import copy
import hashlib
import hmac
import json
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fdikit.decision import ThresholdEvaluator
from fdikit.detector import Detector
from fdikit.detector_file import REGISTRY, SUPPORTED_VERSIONS, load_detector, save_detector
from fdikit.errors import DataError
from fdikit.operating_point import OperatingPoint
from test_detector import bank, detectors, test_trace

HERE = Path(__file__).parent


@pytest.fixture(scope="module")
def all_detectors():
    return detectors()


@pytest.fixture
def small_file(tmp_path, all_detectors):
    return save_detector(all_detectors["threshold"], tmp_path / "threshold.json")


def body_digest(doc: dict, key: bytes | None = None) -> dict:
    """The digest of ``{"format", "payload", "version"}`` as the format defines it (compact, sorted, ASCII)."""
    body = {k: doc[k] for k in ("format", "version", "payload")}
    msg = json.dumps(body, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode("ascii")
    if key is None:
        return {"algorithm": "sha256", "value": hashlib.sha256(msg).hexdigest()}
    return {"algorithm": "hmac-sha256", "value": hmac.new(key, msg, hashlib.sha256).hexdigest()}


def rewrite(path: Path, mutate, key: bytes | None = None) -> Path:
    """A naive edit: change the content, recompute the plain digest, write the canonical text."""
    doc = json.loads(path.read_text())
    mutate(doc)
    doc["digest"] = body_digest(doc, key)
    path.write_text(json.dumps(doc, sort_keys=True, indent=1, ensure_ascii=True) + "\n")
    return path


# ------------------------------------------------------------------------------------------ fresh process
def outputs(det: Detector, tr) -> dict:
    """Everything a deployment produces: batch residuals and decisions, online residuals and decisions."""
    res, diag = det.residuals(tr), det.run(tr)
    s = det.online()
    steps, r_on = [], []
    for k in range(len(tr)):
        steps.append(s.step(tr.u[k], tr.y[k], valid=bool(tr.valid[k])))
        r_on.append(s.residuals)
    out = {"r": res.r, "valid": res.valid, "recovering": res.recovering, "alarm": diag.alarm,
           "fired": diag.fired, "isolated": diag.isolated.astype(str), "used": diag.valid,
           "on_r": np.array(r_on), "on_alarm": np.array([d.alarm for d in steps]),
           "on_fault": np.array([d.fault for d in steps], dtype=str), "on_fired": np.array([d.fired for d in steps]),
           "on_valid": np.array([d.valid for d in steps])}
    if diag.probabilities is not None:
        out["prob"] = diag.probabilities
        out["on_prob"] = np.array([d.probabilities for d in steps])
    return out


def child_main(folder: str) -> None:
    """Run in the child: load every detector file with pickle disabled and np.save what it produces."""
    d = Path(folder)
    from fdikit.trace import Trace

    z = np.load(d / "trace.npz", allow_pickle=False)
    tr = Trace(z["t"], z["u"], z["y"], ("u",), ("y1", "y2"), valid=z["valid"])
    for p in sorted(d.glob("*.json")):
        np.savez(d / f"{p.stem}.out.npz", **outputs(load_detector(p), tr))


# pickle is refused everywhere but in numba's cache of the package's own compiled kernels (the residual
# generator's batch kernel, fdikit.runtime.lti_batch): that cache is written by the installation, not read from
# the detector file, which must never be unpickled.
CHILD = """
import pickle, sys
def guarded(original):
    def load(*args, **kwargs):
        if sys._getframe(1).f_globals.get("__name__") == "numba.core.caching":
            return original(*args, **kwargs)
        raise AssertionError("pickle used in the load path")
    return load
pickle.load, pickle.loads = guarded(pickle.load), guarded(pickle.loads)
pickle.Unpickler = guarded(pickle.Unpickler)
sys.path.insert(0, sys.argv[1])
import test_detector_file
test_detector_file.child_main(sys.argv[2])
"""


def test_saved_detectors_give_bit_identical_residuals_and_decisions_in_a_fresh_process(tmp_path, all_detectors):
    tr = test_trace()
    np.savez(tmp_path / "trace.npz", t=tr.t, u=tr.u, y=tr.y, valid=tr.valid)
    op = OperatingPoint(u0={"u": 1.5}, y0={"y1": 10.0, "y2": 20.0})
    dets = dict(all_detectors)
    dets["operating_point"] = Detector(bank(op), all_detectors["cusum"].evaluator, residual_cov=np.diag([0.02, 0.05]),
                                       recovery_tol=0.05, name="with offsets")
    for kind, det in dets.items():
        save_detector(det, tmp_path / f"{kind}.json")
    proc = subprocess.run([sys.executable, "-c", CHILD, str(HERE), str(tmp_path)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    for kind, det in dets.items():
        mine = outputs(det, tr)
        with np.load(tmp_path / f"{kind}.out.npz", allow_pickle=False) as theirs:
            assert sorted(theirs.files) == sorted(mine)
            for name, value in mine.items():
                other = theirs[name]
                assert other.dtype == value.dtype and other.shape == value.shape, (kind, name)
                assert other.tobytes() == value.tobytes(), (kind, name)  # bit for bit, NaN and -0.0 included
        assert mine["alarm"].any(), kind  # the comparison covers alarms, not only silence


# ------------------------------------------------------------------------------------------ the text
def test_the_file_is_canonical_json_with_the_documented_fields(small_file):
    text = small_file.read_text(encoding="ascii")
    doc = json.loads(text)
    assert set(doc) == {"digest", "format", "payload", "version"}
    assert (doc["format"], doc["version"]) == ("fdikit-detector", 1)
    assert doc["digest"] == body_digest(doc)
    assert text == json.dumps(doc, sort_keys=True, indent=1, ensure_ascii=True) + "\n"
    p = doc["payload"]
    assert p["signals"] == {"controls": ["u"], "outputs": ["y1", "y2"], "residuals": ["r1", "r2"]}
    assert p["log"] == {"units": {"y1": "deg"}, "columns": {"y2": "Y2_LOG"}, "time": None}
    assert p["evaluator"]["class"] == "ThresholdEvaluator" and p["generator"]["class"] == "ResidualGenerator"
    A = p["generator"]["fields"]["A"]
    assert (A["$"], A["dtype"], A["shape"]) == ("ndarray", "<f8", [2, 2])


def test_no_pickle_in_the_load_path(small_file, monkeypatch, all_detectors):
    def refuse(*args, **kwargs):
        raise AssertionError("pickle used")

    expected = all_detectors["threshold"].run(test_trace()).alarm.tolist()  # loads numba's kernel cache first
    for name in ("load", "loads", "Unpickler"):
        monkeypatch.setattr(pickle, name, refuse)
    det = load_detector(small_file)
    assert det.run(test_trace()).alarm.tolist() == expected
    source = (Path(__file__).parents[1] / "src/fdikit/detector_file.py").read_text()
    assert "import pickle" not in source and "eval(" not in source and "exec(" not in source


# ------------------------------------------------------------------------------------------ refusals
def test_changed_bytes_are_refused(small_file):
    """A byte replaced by another printable one: JSON breaks, the digest fails, or the text is no longer
    canonical — never a silent load.  Every byte of the digest and the first fields, then every 5th (every
    kind of content: keys, numbers, base64, white space), to keep the test fast on a loaded machine."""
    raw = small_file.read_bytes()
    bad = small_file.with_name("bad.json")
    for i, b in enumerate(raw):
        if i >= 300 and i % 5:
            continue
        c = ord("0") + (b - ord("0") + 1) % 10 if chr(b).isdigit() else (ord("x") if b != ord("x") else ord("y"))
        bad.write_bytes(raw[:i] + bytes([c]) + raw[i + 1:])
        with pytest.raises(DataError):
            load_detector(bad)
    assert len(raw) > 2000


@pytest.mark.parametrize("keep", [0, 1, 100, 0.5, -2, -1])
def test_a_truncated_file_is_refused(small_file, keep):
    raw = small_file.read_bytes()
    n = int(len(raw) * keep) if isinstance(keep, float) else keep % len(raw) if keep < 0 else keep
    small_file.write_bytes(raw[:n])
    with pytest.raises(DataError, match="truncated|canonical|not a fdikit"):
        load_detector(small_file)


def test_an_unknown_version_is_refused_naming_it_and_the_supported_ones(small_file):
    rewrite(small_file, lambda doc: doc.update(version=2))
    with pytest.raises(DataError, match=r"version 2; this fdikit reads versions \[1\]"):
        load_detector(small_file)
    rewrite(small_file, lambda doc: doc.update(version="1"))
    with pytest.raises(DataError, match="version '1'"):
        load_detector(small_file)
    assert SUPPORTED_VERSIONS == (1,)


def test_a_class_outside_the_allowlist_is_refused(small_file, monkeypatch):
    import importlib

    imported = []
    real = importlib.import_module
    monkeypatch.setattr(importlib, "import_module", lambda name, *a: imported.append(name) or real(name, *a))

    def swap(doc):
        doc["payload"]["evaluator"]["class"] = "subprocess:Popen"

    rewrite(small_file, swap)
    with pytest.raises(DataError, match="'subprocess:Popen' is not on the allowlist"):
        load_detector(small_file)
    assert not any("subprocess" in name for name in imported)
    assert "subprocess:Popen" not in REGISTRY and all(v.startswith("fdikit.") for v in REGISTRY.values())


def test_edits_that_keep_the_content_and_other_malformed_files_are_refused(small_file):
    raw = small_file.read_text()
    small_file.write_text(raw.replace('"format"', ' "format"', 1))
    with pytest.raises(DataError, match="canonical"):
        load_detector(small_file)
    small_file.write_text(raw.replace('{\n "digest"', '{\n "format": "x",\n "digest"', 1))
    with pytest.raises(DataError, match="repeated key"):
        load_detector(small_file)
    small_file.write_text('{"format": "fdikit-detector", "version": NaN}')
    with pytest.raises(DataError, match="NaN"):
        load_detector(small_file)
    small_file.write_text('{"hello": 1}\n')
    with pytest.raises(DataError, match="not a fdikit detector file"):
        load_detector(small_file)
    small_file.write_bytes(b"\xff\xfe")
    with pytest.raises(DataError, match="not ASCII"):
        load_detector(small_file)
    with pytest.raises(DataError, match="cannot read"):
        load_detector(small_file.with_name("missing.json"))


def test_a_plain_digest_stops_damage_not_deliberate_edits_a_key_stops_both(tmp_path, all_detectors):
    det = all_detectors["threshold"]

    def raise_threshold(doc):
        doc["payload"]["evaluator"]["fields"]["alpha"] = 0.5

    # plain SHA-256: a deliberate edit with a recomputed digest loads (documented limitation)
    plain = rewrite(save_detector(det, tmp_path / "plain.json"), raise_threshold)
    assert load_detector(plain).evaluator.alpha == 0.5
    with pytest.raises(DataError, match="authenticity cannot be checked"):
        load_detector(plain, key="secret")
    # HMAC-SHA256: the key is needed, a wrong key or an edit (even with a fresh plain digest) is refused
    signed = save_detector(det, tmp_path / "signed.json", key="secret")
    assert json.loads(signed.read_text())["digest"] == body_digest(json.loads(signed.read_text()), b"secret")
    back = load_detector(signed, key=b"secret")
    assert back.run(test_trace()).alarm.tolist() == det.run(test_trace()).alarm.tolist()
    with pytest.raises(DataError, match="pass key="):
        load_detector(signed)
    with pytest.raises(DataError, match="key is wrong or the file was modified"):
        load_detector(signed, key="guess")
    rewrite(signed, raise_threshold)
    with pytest.raises(DataError, match="authenticity cannot be checked"):
        load_detector(signed, key="secret")
    rewrite(signed, raise_threshold, key=b"guess")
    with pytest.raises(DataError, match="digest does not match"):
        load_detector(signed, key="secret")


def test_an_attribute_of_an_unsupported_type_is_refused_naming_evaluator_and_attribute(tmp_path, all_detectors):
    det = all_detectors["threshold"]
    path = save_detector(det, tmp_path / "d.json")
    before = path.read_bytes()
    ev = copy.deepcopy(det.evaluator)
    ev.callback = print
    with pytest.raises(DataError, match=r"the evaluator ThresholdEvaluator\.callback is a builtins"):
        save_detector(Detector(det.generator, ev), path)
    assert path.read_bytes() == before  # nothing written

    class Custom(ThresholdEvaluator):
        pass

    ev2 = Custom(thresholds=[1.0, 1.0])
    with pytest.raises(DataError, match="Custom"):
        save_detector(Detector(det.generator, ev2), path)


def test_every_supported_value_round_trips_exactly(tmp_path):
    """Arrays bit for bit (NaN payload, −0.0, subnormals, infinities), dtypes, shapes, read-only flags, numpy
    scalars, non-finite floats, big ints, tuples vs lists, ordered dicts with any keys, sets, a Generator."""
    ev = ThresholdEvaluator(thresholds=[1.0, 2.0])
    nan_payload = np.array([0x7FF8000000000123], dtype=np.uint64).view(np.float64)
    ro = np.arange(6.0).reshape(2, 3)
    ro.setflags(write=False)
    rng = np.random.default_rng(123)
    rng.standard_normal(7)
    extra = {
        "f": np.array([nan_payload[0], -0.0, 5e-324, np.inf, -np.inf, 1 / 3]),
        "i32": np.array([[1, -2], [3, 2**31 - 1]], dtype=np.int32), "u8": np.arange(3, dtype=np.uint8),
        "b": np.array([True, False]), "c": np.array([1 + 2j, -0.0 - 1j]), "s": np.array(["none", "y1_sensor"]),
        "zero_d": np.array(2.5), "empty": np.zeros((0, 3)), "ro": ro, "f32": np.float32(0.1), "i64": np.int64(-7),
        "pyfloat": [float("nan"), float("-inf"), -0.0, 0.1], "big": 2**80, "tup": (1, (2.0, "x"), None),
        "lst": [1, [2, 3]], "dct": {"b": 1, 3: "three", (1, "a"): [True], None: 0.5}, "st": frozenset({"a", "b"}),
        "rng": rng,
    }
    for k, v in extra.items():
        setattr(ev, f"x_{k}", v)
    g = bank()
    path = save_detector(Detector(g, ev), tmp_path / "d.json")
    back = load_detector(path)
    for k, v in extra.items():
        w = getattr(back.evaluator, f"x_{k}")
        assert type(w) is type(v), k
        if isinstance(v, (np.ndarray, np.generic)):
            assert w.dtype == v.dtype and np.shape(w) == np.shape(v) and w.tobytes() == v.tobytes(), k
    assert not back.evaluator.x_ro.flags.writeable and back.evaluator.x_f.flags.writeable
    assert np.isnan(back.evaluator.x_pyfloat[0]) and back.evaluator.x_pyfloat[1:3] == [float("-inf"), -0.0]
    assert str(back.evaluator.x_pyfloat[2]) == "-0.0"
    assert back.evaluator.x_big == 2**80 and back.evaluator.x_tup == (1, (2.0, "x"), None)
    assert list(back.evaluator.x_dct.items()) == list(extra["dct"].items())
    assert back.evaluator.x_rng.standard_normal(3).tolist() == rng.standard_normal(3).tolist()
    for name in ("A", "B", "C", "D"):
        assert getattr(back.generator, name).tobytes() == getattr(g, name).tobytes()
        assert not getattr(back.generator, name).flags.writeable


@pytest.mark.parametrize("field", ["run", "reset", "__class__", "not an identifier"])
def test_a_stored_attribute_cannot_shadow_a_method(small_file, field):
    def add(doc):
        doc["payload"]["evaluator"]["fields"][field] = "x"

    rewrite(small_file, add)
    with pytest.raises(DataError, match="would replace a method|not an attribute name"):
        load_detector(small_file)


def test_a_malformed_value_is_refused_as_data(small_file):
    def break_array(doc):
        doc["payload"]["generator"]["fields"]["A"]["shape"] = [3, 3]  # 4 values stored

    original = small_file.read_bytes()
    cases = [(break_array, "32 bytes for an array of shape"),
             (lambda doc: doc["payload"]["evaluator"].pop("fields"), "without a 'fields' mapping"),
             (lambda doc: doc["payload"].pop("log"), "lacks or misshapes")]
    for mutate, message in cases:
        small_file.write_bytes(original)
        rewrite(small_file, mutate)
        with pytest.raises(DataError, match=message):
            load_detector(small_file)
