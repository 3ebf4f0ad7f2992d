"""A campaign's results folder: the manifest, one atomically written Parquet file per chunk, resumption.

``OUT/campaign.json``
    The manifest: format, the campaign's name, the spec (as validated), its fingerprint
    (:func:`fdikit.campaign.spec.spec_fingerprint`: spec + fdikit version), the sweep levels, the numbers of
    runs and chunks, the designs and evaluators.  Written atomically before any run.
``OUT/runs/chunk-NNNNNN.parquet``
    The rows of one chunk (:data:`fdikit.campaign.schema.SCHEMA`), written atomically
    (:mod:`fdikit.atomic`) as soon as the chunk is complete; its Parquet metadata repeats the fingerprint,
    the chunk and its row count.  ``pandas.read_parquet(OUT / "runs")`` reads the dataset (temporary files
    start with a dot and are ignored).

The rules (those of :mod:`fdikit.resume`):

* **the same spec** — a rerun resumes: a chunk file is reused when its metadata names this fingerprint and
  chunk and holds the expected rows; every other chunk is computed.  A chunk's file appears whole or not at
  all, so a kill loses at most the chunks being computed, and a chunk is never stored twice.
* **another spec** (or fdikit version) — refused before any work, naming the entries that differ; rerun
  with the old spec, choose another folder, or pass ``fresh=True`` (``--fresh``): the new campaign is then
  written to ``runs.next/`` beside a ``campaign.next.json`` (a kill there resumes too) and replaces the old
  results only once it is complete.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from fdikit.atomic import write_bytes, write_text
from fdikit.campaign.spec import CampaignSpec, spec_fingerprint, sweep_levels
from fdikit.errors import DataError, ParameterError

__all__ = ["CampaignStore", "read_manifest", "load_results", "chunk_file", "encode_chunk", "MANIFEST", "FORMAT"]

#: Name of the manifest file.
MANIFEST = "campaign.json"
#: Version of the folder layout.
FORMAT = 1
_META = b"fdikit.campaign"


def read_manifest(folder: str | Path) -> dict:
    """The manifest of a results folder.

    Parameters
    ----------
    folder : str or Path

    Returns
    -------
    dict

    Raises
    ------
    DataError
        When the folder holds no campaign (no ``campaign.json``) or the manifest is unreadable.

    Examples
    --------
    >>> import tempfile
    >>> read_manifest(tempfile.mkdtemp())  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    fdikit.errors.DataError: ... holds no campaign results (no campaign.json); run `fdikit campaign run ...` first
    """
    path = Path(folder) / MANIFEST
    if not path.is_file():
        raise DataError(f"{folder} holds no campaign results (no {MANIFEST}); run `fdikit campaign run SPEC "
                        "--out ...` first")
    try:
        manifest = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise DataError(f"{path} is unreadable ({exc}); rerun the campaign with --fresh") from None
    if manifest.get("format") != FORMAT:
        raise DataError(f"{path} has layout format {manifest.get('format')!r}, this fdikit reads {FORMAT}")
    return manifest


def load_results(folder: str | Path, *, complete: bool = True):
    """The manifest and the results table of a campaign folder.

    Parameters
    ----------
    folder : str or Path
    complete : bool, default True
        Refuse a campaign that is not finished (a chunk missing); False reads what there is.

    Returns
    -------
    (dict, pandas.DataFrame)
        The manifest and the rows sorted by run, design and evaluator.

    Raises
    ------
    DataError
        When the folder holds no campaign, or (``complete``) chunks are missing.

    Examples
    --------
    >>> manifest, table = load_results("out/campaign/path-linear")  # doctest: +SKIP
    >>> table.groupby(["design", "evaluator"]).detected.mean()  # doctest: +SKIP
    """
    import pandas as pd

    from fdikit.campaign.schema import empty_table

    manifest = read_manifest(folder)
    data = Path(folder) / "runs"
    files = sorted(data.glob("chunk-*.parquet")) if data.is_dir() else []
    if complete and len(files) != manifest["chunks"]:
        raise DataError(f"{folder}: the campaign is not complete ({len(files)} of {manifest['chunks']} chunks); "
                        "rerun `fdikit campaign run` with the same spec to finish it")
    table = pd.read_parquet(data) if files else empty_table().to_pandas()
    return manifest, table.sort_values(["run", "design", "evaluator"], kind="stable").reset_index(drop=True)


class CampaignStore:
    """The results folder of one campaign spec (module docstring).

    Parameters
    ----------
    folder : str or Path
        Created when missing.
    spec : CampaignSpec
    runs, chunks : int
        Numbers of runs and chunks of the plan.
    fresh : bool, default False
        Replace results of another spec (module docstring).

    Raises
    ------
    ParameterError
        When the folder holds results of another spec and ``fresh`` is False.

    Examples
    --------
    >>> import tempfile
    >>> from fdikit.campaign.spec import CampaignSpec
    >>> spec = CampaignSpec.model_validate({"name": "x", "study": "path-linear", "duration": 1.0,
    ...     "plants": [{"name": "linear"}], "healthy": 1, "designs": [{"name": "k", "kind": "kalman"}],
    ...     "evaluators": [{"name": "t", "kind": "threshold"}]})
    >>> store = CampaignStore(tempfile.mkdtemp(), spec, runs=1, chunks=1)
    >>> store.done_chunks(), store.rows_per_run
    (set(), 1)
    """

    def __init__(self, folder: str | Path, spec: CampaignSpec, *, runs: int, chunks: int, fresh: bool = False):
        self.folder = Path(folder)
        if self.folder.exists() and not self.folder.is_dir():
            raise ParameterError(f"out: {self.folder} is a file; give a folder for the campaign's results")
        self.spec = spec
        self.fingerprint = spec_fingerprint(spec)
        self.levels = sweep_levels(spec.sweep)
        self.rows_per_run = len(spec.designs) * len(spec.evaluators)
        self.chunk_size = spec.chunk_size
        self.runs, self.chunks = runs, chunks
        self.manifest = {
            "format": FORMAT, "name": spec.name, "fingerprint": self.fingerprint, "fdikit": _version(),
            "spec": spec.model_dump(mode="json"), "levels": self.levels, "runs": runs, "chunks": chunks,
            "duration": spec.duration, "designs": [d.name for d in spec.designs],
            "evaluators": [e.name for e in spec.evaluators],
        }
        self.staged = False
        current = self._manifest(MANIFEST)
        if current is None or current.get("fingerprint") == self.fingerprint:
            self.data = self.folder / "runs"
            if current is None:
                write_text(self.folder / MANIFEST, json.dumps(self.manifest, indent=1))
            return
        if not fresh:
            raise ParameterError(f"out: {self.folder} holds the results of another campaign spec "
                                 f"({_differences(current, self.manifest)}); rerun with that spec to resume it, "
                                 "choose another folder, or pass fresh=True (--fresh) to replace them")
        self.staged = True
        self.data = self.folder / "runs.next"
        staged = self._manifest("campaign.next.json")
        if staged is None or staged.get("fingerprint") != self.fingerprint:
            shutil.rmtree(self.data, ignore_errors=True)  # an abandoned, incomplete fresh run of a third spec
            write_text(self.folder / "campaign.next.json", json.dumps(self.manifest, indent=1))

    def _manifest(self, name: str) -> dict | None:
        path = self.folder / name
        if not path.is_file():
            return None
        try:
            return json.loads(path.read_text())
        except (OSError, ValueError):
            return {}

    def _expected_rows(self, chunk: int) -> int:
        first = chunk * self.chunk_size
        return (min(first + self.chunk_size, self.runs) - first) * self.rows_per_run

    def done_chunks(self) -> set[int]:
        """The chunks whose files are complete and belong to this spec (removing a killed run's temporary files)."""
        import pyarrow.parquet as pq

        done = set()
        if not self.data.is_dir():
            return done
        for tmp in self.data.glob(".chunk-*.tmp"):
            tmp.unlink(missing_ok=True)
        for path in self.data.glob("chunk-*.parquet"):
            try:
                meta = json.loads(pq.read_metadata(path).metadata[_META])
            except Exception:  # noqa: BLE001 - an unreadable file is recomputed, whatever the reader says
                continue
            c = meta.get("chunk")
            if (meta.get("fingerprint") == self.fingerprint and isinstance(c, int) and 0 <= c < self.chunks
                    and path.name == chunk_file(c) and meta.get("rows") == self._expected_rows(c)):
                done.add(c)
        return done

    def write_chunk(self, chunk: int, data: bytes) -> Path:
        """Store a chunk's Parquet bytes (from :func:`encode_chunk`) atomically; returns the file."""
        return write_bytes(self.data / chunk_file(chunk), data)

    def finish(self) -> None:
        """After the last chunk: a fresh campaign replaces the old results (module docstring)."""
        if not self.staged:
            return
        old = self.folder / "runs"
        retired = self.folder / "runs.old"
        shutil.rmtree(retired, ignore_errors=True)
        if old.exists():
            old.rename(retired)
        self.data.rename(old)
        write_text(self.folder / MANIFEST, json.dumps(self.manifest, indent=1))
        (self.folder / "campaign.next.json").unlink(missing_ok=True)
        shutil.rmtree(retired, ignore_errors=True)
        self.data, self.staged = old, False


def chunk_file(chunk: int) -> str:
    """File name of a chunk.

    Parameters
    ----------
    chunk : int

    Returns
    -------
    str
        ``chunk-NNNNNN.parquet``.

    Examples
    --------
    >>> chunk_file(12)
    'chunk-000012.parquet'
    """
    return f"chunk-{chunk:06d}.parquet"


def encode_chunk(rows: list[dict], fingerprint: str, chunk: int) -> bytes:
    """Parquet bytes of a chunk's rows, with the fingerprint, chunk and row count in the file's metadata.

    Parameters
    ----------
    rows : list of dict
        Rows of :data:`fdikit.campaign.schema.SCHEMA`.
    fingerprint : str
        The spec's fingerprint.
    chunk : int
        The chunk index.

    Returns
    -------
    bytes
        A zstd-compressed Parquet file.

    Examples
    --------
    >>> import json, pyarrow as pa, pyarrow.parquet as pq
    >>> data = encode_chunk([], "ab" * 32, 3)
    >>> json.loads(pq.read_metadata(pa.BufferReader(data)).metadata[b"fdikit.campaign"])["chunk"]
    3
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    from fdikit.campaign.schema import table_from_rows

    table = table_from_rows(rows)
    meta = json.dumps({"fingerprint": fingerprint, "chunk": chunk, "rows": table.num_rows}).encode()
    table = table.replace_schema_metadata({_META: meta})
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink, compression="zstd")
    return sink.getvalue().to_pybytes()


def _version() -> str:
    import fdikit

    return fdikit.__version__


def _differences(old: dict, new: dict) -> str:
    if old.get("fdikit") != new["fdikit"]:
        return f"made by fdikit {old.get('fdikit')}, this is {new['fdikit']}"
    a, b = old.get("spec") or {}, new["spec"]
    keys = sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k))
    return "entries that differ: " + ", ".join(keys) if keys else "an unreadable manifest"
