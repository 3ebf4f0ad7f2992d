"""Bad input for the ``fdikit`` command line: every command refuses it at once, naming the option.

Each case runs ``fdikit ARGS`` in-process (typer's CliRunner) and passes when the command exits
non-zero, prints no traceback, and the message names the option and the problem.  The long
commands (``compare-evaluators``, ``multiple-model``, ``target-tracking``, ``demo``) must refuse
bad arguments before any design or simulation, so every case here takes milliseconds.

Unwritable places are ``/dev/null/...`` (a file as a parent folder) and ``/proc/...`` (no new
entries even for root), so the cases hold when the suite runs as root.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pytest
from harness import check, cli_case, ids

# An output folder holding the manifest of an earlier run made with other arguments
# (the format of fdikit.resume: OUT/run.json).
_OLD = Path(tempfile.mkdtemp(prefix="fdikit-bad-cli-"))
for _cmd, _args in (("multiple-model", {"runs": 2, "seed": 0, "msd_dt": 0.01, "model_sets": 15}),
                    ("compare-evaluators", {"runs_per_fault": 2, "healthy_runs": 5, "seed": 7})):
    (_OLD / _cmd).mkdir()
    (_OLD / _cmd / "run.json").write_text(json.dumps({"command": _cmd, "arguments": _args, "fdikit": "0.1.0",
                                                      "parts": "parts-0000", "fingerprint": "0" * 64}))
(_OLD / "broken").mkdir()
(_OLD / "broken" / "run.json").write_text("{not json")
_FILE = "/dev/null"          # exists, is not a folder
_UNDER_FILE = "/dev/null/x"  # its parent is a file
_PROC = "/proc/fdikit-no-such/x"

CASES = [
    # general
    cli_case("unknown-command", ["nosuch"], "no such command"),
    cli_case("plants-extra-arg", ["plants", "x"], "unexpected extra argument"),
    # demo
    cli_case("demo-unknown-method", ["demo", "--method", "nope"], "method", "'nope'", "bank"),
    cli_case("demo-seed-string", ["demo", "--seed", "abc"], "--seed", "integer"),
    cli_case("demo-seed-negative", ["demo", "--seed", "-1"], "--seed", ">= 0"),
    cli_case("demo-out-is-file", ["demo", "--out", _FILE], "--out", "not a folder"),
    cli_case("demo-out-under-file", ["demo", "--out", _UNDER_FILE], "--out", "cannot"),
    cli_case("demo-out-proc", ["demo", "--out", _PROC], "--out", "cannot"),
    # simulate
    cli_case("simulate-unknown-plant", ["simulate", "nosuchplant"], "nosuchplant", "path12"),
    cli_case("simulate-duration-string", ["simulate", "path12", "--duration", "abc"], "--duration", "number"),
    cli_case("simulate-duration-zero", ["simulate", "path12", "--duration", "0"], "--duration", "> 0"),
    cli_case("simulate-duration-negative", ["simulate", "path12", "--duration", "-5"], "--duration", "> 0"),
    cli_case("simulate-duration-nan", ["simulate", "path12", "--duration", "nan"], "--duration", "finite"),
    cli_case("simulate-duration-inf", ["simulate", "path12", "--duration", "inf"], "--duration", "finite"),
    cli_case("simulate-dt-zero", ["simulate", "path12", "--dt", "0"], "--dt", "> 0"),
    cli_case("simulate-dt-negative", ["simulate", "path12", "--dt", "-0.01"], "--dt", "> 0"),
    cli_case("simulate-dt-nan", ["simulate", "path12", "--dt", "nan"], "--dt", "finite"),
    cli_case("simulate-dt-above-duration", ["simulate", "path12", "--duration", "1", "--dt", "2"],
             "--dt", "--duration"),
    cli_case("simulate-noise-negative", ["simulate", "path12", "--noise-std", "-0.1"], "--noise-std", ">= 0"),
    cli_case("simulate-noise-nan", ["simulate", "path12", "--noise-std", "nan"], "--noise-std", "finite"),
    cli_case("simulate-noise-string", ["simulate", "path12", "--noise-std", "loud"], "--noise-std", "number"),
    cli_case("simulate-seed-negative", ["simulate", "path12", "--seed", "-1"], "--seed", ">= 0"),
    cli_case("simulate-seed-float", ["simulate", "path12", "--seed", "1.5"], "--seed", "integer"),
    cli_case("simulate-param-no-equals", ["simulate", "single-track", "-p", "speed"], "--param", "name=value"),
    cli_case("simulate-param-no-name", ["simulate", "single-track", "-p", "=20"], "--param", "name=value"),
    cli_case("simulate-param-string-number", ["simulate", "single-track", "-p", "speed=fast"],
             "--param", "speed", "number"),
    cli_case("simulate-param-nan", ["simulate", "single-track", "-p", "speed=nan"], "--param", "speed", "finite"),
    cli_case("simulate-param-unknown", ["simulate", "path12", "-p", "nosuch=1"], "nosuch", "path12"),
    cli_case("simulate-param-twice", ["simulate", "single-track", "-p", "speed=20", "-p", "speed=30"],
             "--param", "speed", "twice"),
    cli_case("simulate-fault-unknown-signal", ["simulate", "path12", "-f", "bias:nope:1@1"], "nope"),
    cli_case("simulate-fault-unknown-kind", ["simulate", "path12", "-f", "gremlin:yaw_rate:1"], "gremlin", "kind"),
    cli_case("simulate-fault-string-size", ["simulate", "path12", "-f", "bias:yaw_rate:abc"],
             "bias:yaw_rate:abc", "number"),
    cli_case("simulate-out-is-folder", ["simulate", "path12", "--out", tempfile.gettempdir()], "--out", "folder"),
    cli_case("simulate-out-under-file", ["simulate", "path12", "--out", _UNDER_FILE + ".parquet"], "--out", "cannot"),
    cli_case("simulate-out-proc", ["simulate", "path12", "--out", _PROC + ".parquet"], "--out", "cannot"),
    # compare-evaluators
    cli_case("compare-runs-negative", ["compare-evaluators", "--runs-per-fault", "-1"], "--runs-per-fault", ">= 0"),
    cli_case("compare-runs-string", ["compare-evaluators", "--runs-per-fault", "two"], "--runs-per-fault", "integer"),
    cli_case("compare-runs-float", ["compare-evaluators", "--runs-per-fault", "1.5"], "--runs-per-fault", "integer"),
    cli_case("compare-healthy-negative", ["compare-evaluators", "--healthy-runs", "-2"], "--healthy-runs", ">= 0"),
    cli_case("compare-no-runs", ["compare-evaluators", "--runs-per-fault", "0", "--healthy-runs", "0"],
             "--runs-per-fault", "--healthy-runs", "no test run"),
    cli_case("compare-seed-negative", ["compare-evaluators", "--seed", "-3"], "--seed", ">= 0"),
    cli_case("compare-out-is-file", ["compare-evaluators", "--out", _FILE], "--out", "not a folder"),
    cli_case("compare-out-under-file", ["compare-evaluators", "--out", _UNDER_FILE], "--out", "cannot"),
    cli_case("compare-out-proc", ["compare-evaluators", "--out", _PROC], "--out", "cannot"),
    cli_case("compare-unknown-evaluator", ["compare-evaluators", "--evaluators", "cusum,nope"],
             "--evaluators", "'nope'", "threshold"),
    cli_case("compare-empty-evaluators", ["compare-evaluators", "--evaluators", ","], "--evaluators", "empty"),
    cli_case("compare-bnn-excluded", ["compare-evaluators", "--evaluators", "bnn", "--no-bnn"],
             "--evaluators", "--no-bnn"),
    cli_case("compare-other-arguments",
             ["compare-evaluators", "--seed", "8", "--out", str(_OLD / "compare-evaluators")], "seed", "--fresh"),
    cli_case("compare-broken-manifest", ["compare-evaluators", "--out", str(_OLD / "broken")], "run.json", "--fresh"),
    # target-tracking
    cli_case("tracking-runs-zero", ["target-tracking", "--runs", "0"], "--runs", ">= 1"),
    cli_case("tracking-runs-negative", ["target-tracking", "--runs", "-3"], "--runs", ">= 1"),
    cli_case("tracking-runs-string", ["target-tracking", "--runs", "many"], "--runs", "integer"),
    cli_case("tracking-seed-negative", ["target-tracking", "--seed", "-1"], "--seed", ">= 0"),
    cli_case("tracking-out-is-file", ["target-tracking", "--out", _FILE], "--out", "not a folder"),
    cli_case("tracking-out-proc", ["target-tracking", "--out", _PROC], "--out", "cannot"),
    # multiple-model
    cli_case("mm-msd-dt-zero", ["multiple-model", "--msd-dt", "0"], "--msd-dt", "> 0"),
    cli_case("mm-msd-dt-negative", ["multiple-model", "--msd-dt", "-0.01"], "--msd-dt", "> 0"),
    cli_case("mm-msd-dt-too-large", ["multiple-model", "--msd-dt", "0.05"], "--msd-dt", "0.02"),
    cli_case("mm-msd-dt-nan", ["multiple-model", "--msd-dt", "nan"], "--msd-dt", "finite"),
    cli_case("mm-msd-dt-string", ["multiple-model", "--msd-dt", "fast"], "--msd-dt", "number"),
    cli_case("mm-runs-zero", ["multiple-model", "--runs", "0"], "--runs", ">= 1"),
    cli_case("mm-runs-string", ["multiple-model", "--runs", "x"], "--runs", "integer"),
    cli_case("mm-model-sets-zero", ["multiple-model", "--model-sets", "0"], "--model-sets", ">= 1"),
    cli_case("mm-model-sets-string", ["multiple-model", "--model-sets", "some"], "--model-sets", "integer"),
    cli_case("mm-seed-negative", ["multiple-model", "--seed", "-1"], "--seed", ">= 0"),
    cli_case("mm-out-is-file", ["multiple-model", "--out", _FILE], "--out", "not a folder"),
    cli_case("mm-out-under-file", ["multiple-model", "--out", _UNDER_FILE], "--out", "cannot"),
    cli_case("mm-out-proc", ["multiple-model", "--out", _PROC], "--out", "cannot"),
    cli_case("mm-other-arguments", ["multiple-model", "--runs", "3", "--out", str(_OLD / "multiple-model")],
             "runs", "--fresh"),
    cli_case("mm-broken-manifest", ["multiple-model", "--out", str(_OLD / "broken")], "run.json", "--fresh"),
]


@pytest.mark.parametrize("c", CASES, ids=ids(CASES))
def test_bad_input(c):
    check(c)
