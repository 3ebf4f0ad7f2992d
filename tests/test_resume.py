"""Long commands lose nothing: kill ``compare-evaluators``, ``multiple-model`` and ``target-tracking`` three
times each, resume, compare.

Each command runs in a subprocess (``python -m fdikit.cli``) with small arguments.  A reference run goes
uninterrupted into ``ref/``; the same command into ``run/`` is SIGKILLed three times, each time as soon as
one more finished result (a part file) than at the previous kill exists — for ``compare-evaluators``
after (at least) the 1st, 8th and 15th of its 16 test runs, for ``multiple-model`` after its 1st, 2nd and
3rd of 4 items, for ``target-tracking`` after its 1st, 2nd and 3rd of 4 chunks of runs — and rerun after
each kill.  The resumed results must equal the reference byte for byte
(no file here carries a timing), every part must be kept across the kills (nothing lost), the summary
must hold each result once (nothing duplicated), and no summary file may appear before the run is
complete.  The reference runs go in parallel with the killed ones to keep the wall time down.

The rules of :mod:`fdikit.resume` (refusal on other arguments, ``fresh``, rejected parts, temporary
files) are tested directly on :class:`fdikit.resume.RunStore`, which needs no long computation.
"""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fdikit.errors import ParameterError
from fdikit.resume import MANIFEST, RunStore

COMPARE = ["compare-evaluators", "--runs-per-fault", "1", "--healthy-runs", "1", "--no-bnn",
           "--evaluators", "threshold,cusum,sprt,mhsprt,gaussian-ml"]
MULTIPLE = ["multiple-model", "--runs", "1", "--model-sets", "2", "--msd-dt", "0.02"]
TRACKING = ["target-tracking", "--runs", "4"]  # 4 parts of 1 run
TIMEOUT = 600.0


def _env() -> dict:
    env = dict(os.environ)
    # one BLAS thread per process: the reference and the killed run share the machine
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", COLUMNS="200")
    return env


def _start(args, out: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "fdikit.cli", *args, "--out", str(out)], env=_env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _parts(out: Path) -> list[Path]:
    """The finished parts (``parts-*/<key>.json``; temporary files start with a dot and are not counted)."""
    return sorted(p for p in out.glob("parts-*/*.json") if not p.name.startswith("."))


def _kill_when(args, out: Path, n_parts: int) -> int:
    """Run the command and SIGKILL it as soon as ``n_parts`` parts exist; return the count at the kill."""
    proc = _start(args, out)
    deadline = time.monotonic() + TIMEOUT
    while len(_parts(out)) < n_parts:
        if proc.poll() is not None:
            pytest.fail(f"{args[0]} ended (code {proc.returncode}) before {n_parts} parts existed: "
                        f"{proc.stderr.read().decode()[-2000:]}")
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"{args[0]}: no {n_parts} parts after {TIMEOUT} s")
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    proc.stderr.close()
    assert proc.returncode == -signal.SIGKILL
    return len(_parts(out))


def _finish(proc: subprocess.Popen, what: str) -> None:
    _, err = proc.communicate(timeout=TIMEOUT)
    assert proc.returncode == 0, f"{what}: {err.decode()[-3000:]}"


def _kill_resume_compare(args, out: Path, targets, summaries) -> list[int]:
    """Kill at each target (at least one part more than at the previous kill), resume; parts at each kill."""
    counts, manifest = [], None
    for target in targets:
        before = {p.name: p.read_bytes() for p in _parts(out)}
        n = _kill_when(args, out, max(target, len(before) + 1))
        counts.append(n)
        after = {p.name: p.read_bytes() for p in _parts(out)}
        # nothing lost: every part finished before this run is still there, unchanged
        assert all(after.get(k) == v for k, v in before.items())
        # no summary before the run is complete
        assert not any((out / s).exists() for s in summaries)
        text = (out / MANIFEST).read_text()
        assert manifest in (None, text)  # the resumed run kept the same manifest and parts folder
        manifest = text
    _finish(_start(args, out), f"resumed {args[0]}")
    assert len(list(out.glob("parts-*"))) == 1
    return counts


def _same_files(ref: Path, out: Path, names) -> None:
    for name in names:
        assert (out / name).read_bytes() == (ref / name).read_bytes(), f"{name} differs from the uninterrupted run"
    # the parts themselves are identical too (same fingerprint, same payloads), and no temporary file is left
    ref_parts = {p.name: p.read_bytes() for p in _parts(ref)}
    assert {p.name: p.read_bytes() for p in _parts(out)} == ref_parts
    assert not [p for p in out.rglob(".*") if p.name.endswith(".tmp")]


def test_kill_and_resume_compare_evaluators_and_multiple_model(tmp_path):
    start = time.perf_counter()
    refs = {"compare": _start(COMPARE, tmp_path / "ref_c"), "multiple": _start(MULTIPLE, tmp_path / "ref_m")}

    c_counts = _kill_resume_compare(COMPARE, tmp_path / "run_c", (1, 8, 15), ("scores.csv", "comparison.md"))
    m_counts = _kill_resume_compare(MULTIPLE, tmp_path / "run_m", (1, 2, 3),
                                    ("summary.md", "target_tracking.png", "b747.png", "msd.png"))
    for what, proc in refs.items():
        _finish(proc, f"reference {what}")
    # three different kill points each, strictly increasing
    assert len(set(c_counts)) == 3 and c_counts == sorted(c_counts) and c_counts[-1] < 16, c_counts
    assert m_counts == [1, 2, 3] or (len(set(m_counts)) == 3 and m_counts[-1] < 4), m_counts

    ref, out = tmp_path / "ref_c", tmp_path / "run_c"
    _same_files(ref, out, ("scores.csv", "comparison.md"))
    rows = list(csv.DictReader((out / "scores.csv").open(newline="")))
    pairs = [(r["run"], r["evaluator"]) for r in rows]
    assert len(pairs) == 16 * 5 and len(set(pairs)) == len(pairs)  # every (run, evaluator) once
    assert {int(r) for r, _ in pairs} == set(range(16))

    ref, out = tmp_path / "ref_m", tmp_path / "run_m"
    _same_files(ref, out, ("summary.md", "target_tracking.png", "b747.png", "msd.png"))
    text = (out / "summary.md").read_text()
    for item in ("## Item 17", "## Item 18", "## Item 19", "## Item 20"):
        assert text.count(item) == 1
    # a rerun of a complete run recomputes nothing and rewrites the same files
    before = {p: p.read_bytes() for p in out.iterdir() if p.is_file()}
    _finish(_start(MULTIPLE, out), "rerun of a complete multiple-model")
    assert {p: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    print(f"kill points: compare {c_counts} of 16 runs, multiple-model {m_counts} of 4 items; "
          f"{time.perf_counter() - start:.1f} s")


def test_kill_and_resume_target_tracking(tmp_path):
    ref_proc = _start(TRACKING, tmp_path / "ref")
    counts = _kill_resume_compare(TRACKING, tmp_path / "run", (1, 2, 3), ("summary.md", "rmse.png"))
    _finish(ref_proc, "reference target-tracking")
    assert len(set(counts)) == 3 and counts[-1] < 4, counts
    _same_files(tmp_path / "ref", tmp_path / "run", ("summary.md", "rmse.png"))
    assert len(_parts(tmp_path / "run")) == 4


def test_other_arguments_are_refused_before_any_work(tmp_path):
    """A rerun with other arguments is refused at once, naming the difference; nothing in OUT changes."""
    old = RunStore(tmp_path, "multiple-model", {"runs": 2, "seed": 0})
    old.save("item17", {"section": "x"})
    snapshot = {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()}
    t0 = time.perf_counter()
    from typer.testing import CliRunner

    from fdikit.cli import app

    res = CliRunner().invoke(app, ["multiple-model", "--runs", "3", "--out", str(tmp_path)])
    assert res.exit_code == 2 and "--fresh" in res.output and "runs (--runs) = 2 there, 3 now" in res.output
    assert time.perf_counter() - t0 < 5.0  # refused before any computation
    assert {p: p.read_bytes() for p in tmp_path.rglob("*") if p.is_file()} == snapshot
    with pytest.raises(ParameterError, match="command 'multiple-model' there"):
        RunStore(tmp_path, "compare-evaluators", {"runs": 2, "seed": 0})


def test_resume_reuses_checked_parts_and_rejects_bad_ones(tmp_path):
    store = RunStore(tmp_path, "cmd", {"n": 1})
    store.save("a", {"x": 1.5, "nan": float("nan")}, files={"a.png": b"\x89PNG-a"})
    store.save("b", {"x": 2})
    store.save("c", {"x": 3}, files={"c.png": b"png-c"})
    (store.parts / ".b.json.abcd.tmp").write_bytes(b"half a record")  # left by a kill inside atomic_path
    again = RunStore(tmp_path, "cmd", {"n": 1})
    assert again.resumed and again.parts == store.parts
    assert not list(store.parts.glob(".*.tmp"))
    payload = again.load("a")
    assert payload["x"] == 1.5 and payload["nan"] != payload["nan"]
    # a changed record, a changed side file, a record of other arguments: rejected, recomputed later
    rec = json.loads((store.parts / "b.json").read_text())
    rec["payload"]["x"] = 3
    (store.parts / "b.json").write_text(json.dumps(rec))
    (store.parts / "c.png").write_bytes(b"png-C")
    other = RunStore(tmp_path / "other", "cmd", {"n": 2})
    other.save("d", {"x": 9})  # a valid record, but of the arguments n = 2
    (store.parts / "d.json").write_bytes((other.parts / "d.json").read_bytes())
    assert [again.load(k) for k in "bcd"] == [None, None, None]
    assert again.rejected == ["b", "c", "d"]
    assert again.load("missing") is None


def test_fresh_keeps_old_results_until_the_new_run_is_complete(tmp_path):
    old = RunStore(tmp_path, "cmd", {"n": 1})
    old.save("a", {"x": 1})
    old.publish({"summary.md": "old summary\n"})
    with pytest.raises(ParameterError, match="n \\(--n\\) = 1 there, 2 now"):
        RunStore(tmp_path, "cmd", {"n": 2})
    new = RunStore(tmp_path, "cmd", {"n": 2}, fresh=True)
    assert new.parts != old.parts and not new.resumed
    new.save("a", {"x": 2})
    # killed here: the old summary and the old parts are untouched; a plain rerun resumes the new run
    assert (tmp_path / "summary.md").read_text() == "old summary\n" and old.load("a") == {"x": 1}
    resumed = RunStore(tmp_path, "cmd", {"n": 2})
    assert resumed.parts == new.parts and resumed.load("a") == {"x": 2}
    resumed.publish({"summary.md": "new summary\n"})
    assert (tmp_path / "summary.md").read_text() == "new summary\n"
    assert not old.parts.exists() and new.parts.exists()
    # --fresh with the same arguments starts a new parts folder too (nothing reused)
    again = RunStore(tmp_path, "cmd", {"n": 2}, fresh=True)
    assert again.parts != new.parts and again.load("a") is None


def test_unreadable_manifest_is_refused(tmp_path):
    (tmp_path / MANIFEST).write_text("{broken")
    with pytest.raises(ParameterError, match="run.json.*--fresh"):
        RunStore(tmp_path, "cmd", {})
    (tmp_path / MANIFEST).write_text(json.dumps({"command": "cmd", "arguments": {}, "parts": "../../etc"}))
    with pytest.raises(ParameterError, match="not a valid fdikit run manifest"):
        RunStore(tmp_path, "cmd", {})
    assert RunStore(tmp_path, "cmd", {}, fresh=True).parts.is_dir()
