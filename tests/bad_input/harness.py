"""The bad-input battery: one case per hostile input, each naming the error it must raise.

A case passes when the call raises the expected :class:`fdikit.errors.FdiError` subclass and
the message names the problem (every fragment in ``names`` occurs, case-insensitively).  CLI
cases pass when the command exits non-zero with such a message and no traceback.

Each ``test_*.py`` in this folder defines ``CASES`` (a list of :class:`Case`) and one
parametrised test calling :func:`check`.  ``python tests/bad_input/battery.py`` runs every case
and counts the outcomes (clear error, unclear error, raw exception, silent result), which is
how the before/after figures of ``docs/RELIABILITY.md`` are measured.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from fdikit.errors import FdiError

__all__ = ["Case", "case", "cli_case", "check", "outcome", "ids"]


@dataclass(frozen=True)
class Case:
    """One hostile input: ``call()`` must raise ``error`` with every fragment of ``names`` in its message."""

    id: str
    call: Callable[[], object] | None
    error: type[BaseException]
    names: tuple[str, ...]
    cli_args: tuple[str, ...] | None = field(default=None)


def case(id: str, call: Callable[[], object], error: type[BaseException], *names: str) -> Case:
    """A Python API case."""
    return Case(id, call, error, tuple(names))


def cli_case(id: str, args: Sequence[str], *names: str) -> Case:
    """A CLI case: ``fdikit ARGS`` must exit non-zero, print every fragment of ``names`` and no traceback."""
    return Case(id, None, SystemExit, tuple(names), tuple(str(a) for a in args))


def ids(cases: Sequence[Case]) -> list[str]:
    """pytest ids of the cases (their ``id``)."""
    return [c.id for c in cases]


def _run_cli(args: Sequence[str]):
    from typer.testing import CliRunner

    from fdikit.cli import app

    return CliRunner().invoke(app, list(args))


def outcome(c: Case) -> tuple[str, str]:
    """Classify a case: ('clear' | 'unclear' | 'raw' | 'silent', detail)."""
    if c.cli_args is not None:
        res = _run_cli(c.cli_args)
        text = res.output or ""
        if res.exit_code == 0:
            return "silent", f"exit 0: {text[-200:]!r}"
        if res.exception is not None and not isinstance(res.exception, SystemExit):
            return "raw", f"{type(res.exception).__name__}: {res.exception}"
        if "Traceback" in text:
            return "raw", "traceback printed"
        missing = [n for n in c.names if n.lower() not in text.lower()]
        return ("unclear", f"message lacks {missing}: {text[-300:]!r}") if missing else ("clear", text.strip()[-200:])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c.call()
    except FdiError as exc:
        msg = str(exc)
        if not isinstance(exc, c.error):
            return "unclear", f"{type(exc).__name__} instead of {c.error.__name__}: {msg}"
        missing = [n for n in c.names if n.lower() not in msg.lower()]
        return ("unclear", f"message lacks {missing}: {msg}") if missing else ("clear", msg)
    except Exception as exc:  # noqa: BLE001 - classifying is the point
        return "raw", f"{type(exc).__name__}: {exc}"
    return "silent", "no error raised"


def check(c: Case) -> None:
    """Assert that the case gives a clear error (used by each module's parametrised test)."""
    kind, detail = outcome(c)
    assert kind == "clear", f"{c.id}: {kind} — {detail}"
