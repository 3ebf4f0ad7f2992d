"""Resumable long runs: each finished result in its own checked file, tied to the arguments that made it.

The long commands (``fdikit compare-evaluators``, ``fdikit multiple-model``) keep their work in an
output folder ``OUT``:

``OUT/run.json``
    the manifest: the command, its arguments, the fdikit version and the name of the parts folder.
``OUT/parts-<token>/<key>.json``
    one file per finished result ("part"), written atomically (:mod:`fdikit.atomic`) as soon as the
    result is complete.  It holds the run's fingerprint (SHA-256 of command, arguments and version),
    the payload, the SHA-256 of every side file (a plot) and a SHA-256 of itself; a part is reused
    only when all of these check.
``OUT/<summary files>``
    assembled from the parts, each written atomically, only once every part is complete.

The rule (see ``docs/RELIABILITY.md``):

* **same arguments** — a rerun resumes: finished parts are reused, the others computed.  A kill at
  any moment loses at most the part being computed.
* **other arguments** (or another fdikit version) — the run is refused before any work, naming the
  arguments that differ.  Rerun with the old arguments to resume, choose another output folder, or
  pass ``fresh=True`` (``--fresh``): the new run starts a new parts folder and computes everything;
  the earlier summary files and parts stay untouched until the new run is complete, then the new
  summary files replace them and the old parts folder is removed.
* nothing is ever truncated or deleted before its replacement is complete.

The argument checks used by the long commands (:func:`check_count`, :func:`check_seed`,
:func:`check_output_folder` ...) live here too: every message names the argument both as the
Python parameter and as the command-line option, says what is wrong and what would be accepted.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import numbers
import os
import re
import secrets
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path

from fdikit import validate
from fdikit.atomic import write_bytes, write_text
from fdikit.errors import ParameterError

__all__ = [
    "RunStore",
    "check_count",
    "check_seed",
    "check_positive",
    "check_nonnegative",
    "check_output_folder",
    "check_output_file",
    "option_name",
    "MANIFEST",
]

#: Name of the manifest file in the output folder.
MANIFEST = "run.json"
_FORMAT = 1
_PARTS = re.compile(r"^parts-[0-9a-f]{4,32}$")
_KEY = re.compile(r"^[A-Za-z0-9_.-]{1,100}$")


def option_name(name: str) -> str:
    """``'runs_per_fault'`` → ``"runs_per_fault (--runs-per-fault)"``: how messages name an argument.

    Parameters
    ----------
    name : str
        The Python parameter name.

    Returns
    -------
    str
        The name followed by its command-line option in parentheses.

    Examples
    --------
    >>> option_name("runs_per_fault")
    'runs_per_fault (--runs-per-fault)'
    """
    return f"{name} (--{name.replace('_', '-')})"


def _shown(value) -> str:
    """How a rejected number is quoted: ``repr`` for a non-number, ``nan``/``inf`` as such, others with ``:g``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return repr(value)
    return f"{float(value):g}"


def check_count(value, name: str, minimum: int = 1) -> int:
    """``value`` as a whole number ``>= minimum``; :class:`ParameterError` naming ``name`` otherwise.

    :func:`fdikit.validate.integer` does the check; the message keeps the command-line wording
    (the argument both as parameter and as option, and the accepted range).

    Parameters
    ----------
    value : int
        The count (an ``int`` or numpy integer; a bool or float is refused).
    name : str
        The parameter name, as the message quotes it (with its option, :func:`option_name`).
    minimum : int, default 1
        Smallest accepted value.

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        When ``value`` is not an integer or is below ``minimum``.

    Examples
    --------
    >>> check_count(3, "runs_per_fault")
    3
    >>> check_count(0, "runs_per_fault")
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: runs_per_fault (--runs-per-fault) must be an integer >= 1, got 0
    """
    try:
        return validate.integer(name, value, minimum=minimum)
    except ParameterError:
        raise ParameterError(f"{option_name(name)} must be an integer >= {minimum}, got {value!r}") from None


def check_seed(value, name: str = "seed") -> int:
    """A seed: an integer ``>= 0`` (what :func:`numpy.random.default_rng` accepts).

    Parameters
    ----------
    value : int
        The seed.
    name : str, default "seed"
        The parameter name, as the message quotes it.

    Returns
    -------
    int

    Examples
    --------
    >>> check_seed(0)
    0
    """
    return check_count(value, name, minimum=0)


def check_positive(value, name: str, *, maximum: float | None = None, hint: str = "") -> float:
    """``value`` as a finite float ``> 0`` (and ``<= maximum`` when given): :func:`fdikit.validate.positive`
    with the command-line wording.

    Parameters
    ----------
    value : float
        The number to check.
    name : str
        The parameter name, as the message quotes it (with its option).
    maximum : float, optional
        Largest accepted value (no bound when omitted).
    hint : str, optional
        Appended to the message (what the argument is, what is usual).

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        When ``value`` is not a finite number > 0, or exceeds ``maximum``.

    Examples
    --------
    >>> check_positive(0.05, "alpha", maximum=1)
    0.05
    >>> check_positive(2.0, "alpha", maximum=1)
    Traceback (most recent call last):
    ...
    fdikit.errors.ParameterError: alpha (--alpha) must be at most 1, got 2
    """
    try:
        value = validate.positive(name, value)
    except ParameterError:
        raise ParameterError(f"{option_name(name)} must be a finite number > 0, got {_shown(value)}{hint}") from None
    if maximum is not None and value > maximum:
        raise ParameterError(f"{option_name(name)} must be at most {maximum:g}, got {value:g}{hint}")
    return value


def check_nonnegative(value, name: str) -> float:
    """``value`` as a finite float ``>= 0``: :func:`fdikit.validate.non_negative` with the command-line wording.

    Parameters
    ----------
    value : float
        The number to check.
    name : str
        The parameter name, as the message quotes it (with its option).

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        When ``value`` is not a finite number >= 0.

    Examples
    --------
    >>> check_nonnegative(0, "onset")
    0.0
    """
    try:
        return validate.non_negative(name, value)
    except ParameterError:
        raise ParameterError(f"{option_name(name)} must be a finite number >= 0, got {_shown(value)}") from None


def check_output_file(path, name: str = "out") -> Path:
    """Check that the file ``path`` can be written (its folder is created); it is not written here.

    Parameters
    ----------
    path : str or PathLike
        The file to be written.
    name : str, default "out"
        The parameter name, as the messages quote it (with its option).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    ParameterError
        When ``path`` is not a path, is a folder, or its folder cannot be created or written into.

    Examples
    --------
    >>> import pathlib
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     out = check_output_file(pathlib.Path(tmp) / "new" / "trace.parquet")
    ...     out.name, out.parent.is_dir(), out.exists()
    ('trace.parquet', True, False)
    """
    if not isinstance(path, (str, os.PathLike)) or str(path) == "":
        raise ParameterError(f"{option_name(name)} must be a file path, got {path!r}")
    path = Path(path)
    if path.is_dir():
        raise ParameterError(f"{option_name(name)}: {path} is a folder; give a file name such as "
                             f"{path / 'trace.parquet'}")
    try:
        check_output_folder(path.parent, name)
    except ParameterError as exc:
        raise ParameterError(f"{option_name(name)}: cannot write {path}: {str(exc).split(': ', 1)[-1]}") from None
    return path


def check_output_folder(out, name: str = "out") -> Path:
    """Create the output folder ``out`` if needed and check that files can be written into it.

    Parameters
    ----------
    out : str or PathLike
        The output folder (parents are created too).
    name : str, default "out"
        The parameter name, as the messages quote it (with its option).

    Returns
    -------
    pathlib.Path
        ``out``, which now exists.

    Raises
    ------
    ParameterError
        When ``out`` is not a path, is an existing file, cannot be created, or is not writable.

    Examples
    --------
    >>> import pathlib
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     check_output_folder(pathlib.Path(tmp) / "runs").is_dir()
    True
    """
    if not isinstance(out, (str, os.PathLike)) or str(out) == "":
        raise ParameterError(f"{option_name(name)} must be a folder path, got {out!r}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"{option_name(name)}: {out} is not a folder (a file of that name exists); "
                             "give a folder path")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"{option_name(name)}: cannot create the folder {out} ({exc.strerror or exc}); "
                             "choose a writable place") from None
    try:
        fd, probe = tempfile.mkstemp(prefix=".fdikit-probe-", dir=out)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise ParameterError(f"{option_name(name)}: cannot write into {out} ({exc.strerror or exc}); "
                             "choose a writable folder") from None
    return out


def _canonical(obj) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=True, default=_plain)


def _plain(obj):
    """JSON for numpy scalars and arrays (``.item()`` / ``.tolist()``)."""
    if hasattr(obj, "tolist"):
        return obj.tolist()
    raise TypeError(f"cannot store {type(obj).__name__} in a result part")


def _sha(data: str | bytes) -> str:
    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def plain(obj):
    """``obj`` as it will be read back from a part (numpy scalars → Python numbers, tuples → lists)."""
    return json.loads(_canonical(obj))


class RunStore:
    """The parts of one long run in ``out``, tied to ``command`` and ``arguments`` (see the module doc).

    Parameters
    ----------
    out : str or PathLike
        Output folder; created when missing (checked writable first).
    command : str
        The command name, e.g. ``"multiple-model"``.
    arguments : mapping
        Every argument that changes a result (JSON-serialisable).
    fresh : bool, default False
        Start over in a new parts folder even when ``out`` holds a resumable run.
    out_name : str, default "out"
        The name of ``out`` in the messages (with its option).

    Attributes
    ----------
    out : pathlib.Path
        The output folder.
    parts : pathlib.Path
        The parts folder of this run, ``out/parts-<token>``.
    fingerprint : str
        SHA-256 of command, arguments and fdikit version.
    resumed : bool
        Whether an earlier run of the same arguments is resumed.
    rejected : list of str
        Keys of parts that existed but failed a check (recomputed).

    Raises
    ------
    ParameterError
        When ``out`` is unusable, its ``run.json`` is unreadable, or it holds a run of other arguments
        and ``fresh`` is false.

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     store = RunStore(tmp, "demo", {"seed": 1})
    ...     store.save("a", {"x": (1, 2)})
    ...     again = RunStore(tmp, "demo", {"seed": 1})
    ...     again.resumed, again.load("a"), again.load("b")
    {'x': [1, 2]}
    (True, {'x': [1, 2]}, None)
    """

    def __init__(self, out, command: str, arguments: Mapping, *, fresh: bool = False, out_name: str = "out"):
        from fdikit import __version__

        self.out = check_output_folder(out, out_name)
        self.identity = plain({"command": command, "arguments": dict(arguments), "fdikit": __version__})
        self.fingerprint = _sha(_canonical(self.identity))
        self.rejected: list[str] = []
        old = None if fresh else self._read_manifest()
        if old is not None:
            theirs = {k: old.get(k) for k in ("command", "arguments", "fdikit")}
            if theirs != self.identity:
                raise ParameterError(self._mismatch(theirs))
            self.parts = self.out / old["parts"]
            self.resumed = True
        else:
            self.parts = self.out / f"parts-{secrets.token_hex(4)}"
            self.resumed = False
            manifest = {"format": _FORMAT, **self.identity, "fingerprint": self.fingerprint,
                        "parts": self.parts.name}
            self.parts.mkdir(exist_ok=True)
            write_text(self.out / MANIFEST, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
        self.parts.mkdir(exist_ok=True)
        self._remove_temporaries(self.parts)

    # -- manifest -------------------------------------------------------------------------------
    def _read_manifest(self) -> dict | None:
        path = self.out / MANIFEST
        if not path.exists():
            return None
        hint = ("; pass fresh=True (--fresh) to start over (the results in the folder stay until the new run "
                "is complete) or choose another output folder")
        try:
            old = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise ParameterError(f"{path} is not a readable fdikit run manifest ({exc}){hint}") from None
        if (not isinstance(old, dict) or not isinstance(old.get("parts"), str) or not _PARTS.match(old["parts"])
                or not isinstance(old.get("arguments"), dict)):
            raise ParameterError(f"{path} is not a valid fdikit run manifest (needs 'command', 'arguments' and "
                                 f"'parts'){hint}")
        return old

    def _mismatch(self, theirs: dict) -> str:
        mine = self.identity
        diffs = []
        if theirs["command"] != mine["command"]:
            diffs.append(f"command {theirs['command']!r} there, {mine['command']!r} now")
        if theirs["fdikit"] != mine["fdikit"]:
            diffs.append(f"fdikit {theirs['fdikit']} there, {mine['fdikit']} now")
        a, b = theirs["arguments"] or {}, mine["arguments"]
        for key in sorted(set(a) | set(b)):
            if a.get(key, "(unset)") != b.get(key, "(unset)"):
                diffs.append(f"{option_name(key)} = {a.get(key, '(unset)')!r} there, {b.get(key, '(unset)')!r} now")
        return (f"{self.out} holds results of another run ({'; '.join(diffs) or 'a different fingerprint'}). "
                "Results are reused only with the same arguments: rerun with the arguments shown 'there' to "
                "resume, choose another output folder, or pass fresh=True (--fresh) to start over (the old "
                "results stay until the new run is complete)")

    # -- parts ----------------------------------------------------------------------------------
    def _check_key(self, key: str) -> None:
        if not _KEY.match(key) or key == MANIFEST:
            raise ParameterError(f"part key {key!r} must be 1-100 letters, digits, '_', '.' or '-'")

    def load(self, key: str):
        """The payload of part ``key`` if it is complete and made by this run's arguments, else ``None``.

        A part that exists but fails a check (fingerprint, self-hash, a side file's hash) is noted in
        :attr:`rejected` and treated as not done; it is overwritten when recomputed.
        """
        self._check_key(key)
        path = self.parts / f"{key}.json"
        if not path.exists():
            return None
        try:
            rec = json.loads(path.read_text(encoding="utf-8"))
            body = {k: v for k, v in rec.items() if k != "sha256"}
            ok = (rec.get("sha256") == _sha(_canonical(body)) and rec.get("fingerprint") == self.fingerprint
                  and rec.get("key") == key)
            for name, digest in (rec.get("files") or {}).items() if ok else ():
                side = self.parts / name
                if Path(name).name != name or not side.is_file() or _sha(side.read_bytes()) != digest:
                    ok = False
        except (OSError, UnicodeDecodeError, ValueError, AttributeError):
            ok = False
        if not ok:
            self.rejected.append(key)
            return None
        return rec["payload"]

    def file(self, name: str) -> Path:
        """Path of a side file of a part (in the parts folder)."""
        return self.parts / name

    def save(self, key: str, payload, files: Mapping[str, bytes] | None = None):
        """Write part ``key`` atomically: its side files first, then the record that marks it complete.

        Returns the payload as it will be read back by :meth:`load` (JSON round trip).
        """
        self._check_key(key)
        digests = {}
        for name, data in (files or {}).items():
            if Path(name).name != name or not _KEY.match(name):
                raise ParameterError(f"side file name {name!r} must be a plain file name")
            write_bytes(self.parts / name, data)
            digests[name] = _sha(data)
        body = {"format": _FORMAT, "fingerprint": self.fingerprint, "key": key, "payload": plain(payload),
                "files": digests}
        rec = {**body, "sha256": _sha(_canonical(body))}
        write_text(self.parts / f"{key}.json", _canonical(rec) + "\n")
        return body["payload"]

    def publish(self, files: Mapping[str, bytes | str]) -> list[Path]:
        """Write the assembled result files into ``out`` (atomically, in the given order; put the summary
        last), then remove the parts folders of earlier runs.  Returns the paths written."""
        written = []
        for name, data in files.items():
            data = data.encode("utf-8") if isinstance(data, str) else data
            written.append(write_bytes(self.out / name, data))
        for folder in self.out.iterdir():
            if folder.is_dir() and _PARTS.match(folder.name) and folder != self.parts:
                shutil.rmtree(folder, ignore_errors=True)
        self._remove_temporaries(self.out, names=list(files) + [MANIFEST])
        return written

    @staticmethod
    def _remove_temporaries(folder: Path, names: list[str] | None = None) -> None:
        """Remove the temporary files a killed :func:`fdikit.atomic.atomic_path` left (``.<name>.*.tmp``)."""
        for tmp in folder.glob(".*.tmp"):
            if names is None or any(tmp.name.startswith(f".{n}.") for n in names):
                with contextlib.suppress(OSError):
                    tmp.unlink()
