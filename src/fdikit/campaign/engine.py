"""Run a campaign: chunks of runs on a local process pool or a Dask cluster, each stored as it finishes.

The unit of work is a chunk (``spec.chunk_size`` runs, fixed by the spec).  A worker computes a chunk —
the study's setup (designs, calibrated evaluators) once per worker process, then the chunk's runs — with
its BLAS limited to one thread, and returns the chunk's Parquet bytes; the calling process alone writes
them (:class:`fdikit.campaign.store.CampaignStore`), so a Dask cluster needs no shared file system.
Every chunk is computed from the spec and its index only, with the same code on either backend: the rows
are bit-identical for any number of workers and both backends (tested).

Backends: ``local`` — :class:`concurrent.futures.ProcessPoolExecutor` with the ``spawn`` start method (no
set-up); ``dask`` — :class:`distributed.Client` on ``scheduler`` (a running cluster: ``dask scheduler`` /
``dask worker``), or on a :class:`distributed.LocalCluster` of ``workers`` single-threaded processes when no
address is given.  The Dask dashboard address is printed.
"""

from __future__ import annotations

import hashlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from fdikit.campaign.spec import CampaignSpec
from fdikit.errors import ParameterError

__all__ = ["CampaignRun", "run_campaign", "compute_chunk", "replay", "BACKENDS", "CONNECT_TIMEOUT"]

#: The execution backends.
BACKENDS = ("local", "dask")
#: How long to wait for a Dask scheduler given by address.
CONNECT_TIMEOUT = "20s"

# Per-process caches of the worker: the plan and the study setup of a spec (by fingerprint).  Module
# state on purpose: a worker process computes many chunks of the same campaign and must set up once.
_PLANS: dict[str, list] = {}
_SETUPS: dict[str, object] = {}


@dataclass(frozen=True)
class CampaignRun:
    """What :func:`run_campaign` did.

    Attributes
    ----------
    folder : Path
        The results folder.
    runs, chunks : int
        Runs and chunks of the campaign.
    computed, reused : int
        Chunks computed now and chunks found complete from an earlier run.
    seconds : float
        Wall time of this call.
    workers : int
        Worker processes used.
    backend : str
        ``'local'`` or ``'dask'``.

    Examples
    --------
    >>> from pathlib import Path
    >>> run = CampaignRun(Path("out"), runs=100, chunks=2, computed=1, reused=1, seconds=3.5, workers=2,
    ...                   backend="local")
    >>> run.computed + run.reused == run.chunks
    True
    """

    folder: Path
    runs: int
    chunks: int
    computed: int
    reused: int
    seconds: float
    workers: int
    backend: str


def _plan(spec: CampaignSpec, fingerprint: str) -> list:
    from fdikit.campaign.plan import plan_runs

    if fingerprint not in _PLANS:
        _PLANS[fingerprint] = plan_runs(spec)
    return _PLANS[fingerprint]


def _setup(spec: CampaignSpec, fingerprint: str):
    from fdikit.campaign.studies import get_study

    study = get_study(spec.study)
    if fingerprint not in _SETUPS:
        _SETUPS[fingerprint] = study.setup(spec)
    return study, _SETUPS[fingerprint]


class _numba_threads:  # noqa: N801 - a context manager used like threadpool_limits
    """Limit numba's parallel kernels (:mod:`fdikit.batch`) to ``n`` threads: one worker, one core."""

    def __init__(self, n: int) -> None:
        self.n, self.old = n, None

    def __enter__(self):
        import numba

        self.old = numba.get_num_threads()
        numba.set_num_threads(self.n)
        return self

    def __exit__(self, *exc) -> bool:
        import numba

        numba.set_num_threads(self.old)
        return False


def compute_chunk(spec_json: str, chunk: int) -> bytes:
    """Compute one chunk of a campaign and return its Parquet bytes (what a worker runs).

    Parameters
    ----------
    spec_json : str
        The spec as JSON (``CampaignSpec.model_dump_json()``).
    chunk : int
        The chunk index.

    Returns
    -------
    bytes
        :func:`fdikit.campaign.store.encode_chunk` of the chunk's rows.

    Examples
    --------
    Computing a chunk in the calling process (what a worker does; the first chunk also sets the study up):

    >>> import pyarrow as pa, pyarrow.parquet as pq  # doctest: +SKIP
    >>> from fdikit.campaign.spec import load_campaign
    >>> data = compute_chunk(load_campaign("path-linear").model_dump_json(), 0)  # doctest: +SKIP
    >>> pq.read_table(pa.BufferReader(data)).num_rows  # doctest: +SKIP
    40
    """
    from threadpoolctl import threadpool_limits

    from fdikit.campaign.spec import spec_fingerprint, sweep_levels
    from fdikit.campaign.store import encode_chunk

    spec = CampaignSpec.model_validate_json(spec_json)
    fingerprint = spec_fingerprint(spec)
    with threadpool_limits(1), _numba_threads(1):
        size = spec.chunk_size
        runs = _plan(spec, fingerprint)[chunk * size:(chunk + 1) * size]  # run k is in chunk k // chunk_size
        study, setup = _setup(spec, fingerprint)
        rows = study.run_chunk(setup, spec, runs, sweep_levels(spec.sweep))
    return encode_chunk(rows, fingerprint, chunk)


def _local(spec_json: str, todo: list[int], workers: int, done: Callable, say: Callable) -> None:
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    try:
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            pending = {pool.submit(compute_chunk, spec_json, c): c for c in todo}
            while pending:
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in sorted(finished, key=pending.get):
                    done(pending.pop(fut), fut.result())
    except BrokenProcessPool:
        raise ParameterError("a campaign worker process died (killed, out of memory, or the calling script starts "
                             "the campaign at import: guard it with `if __name__ == \"__main__\":` — worker "
                             "processes import the main module); the chunks finished so far are kept, rerun to "
                             "resume") from None


def _dask(spec_json: str, todo: list[int], workers: int, scheduler: str | None, done: Callable,
          say: Callable) -> int:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:  # pragma: no cover - distributed is a dependency
        raise ParameterError("backend 'dask' needs the distributed package: pip install 'dask[distributed]'") from None
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
        client = Client(cluster)
    else:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT)
        except OSError as exc:
            raise ParameterError(f"scheduler (--scheduler): cannot connect to {scheduler} ({exc}); start one with "
                                 "`dask scheduler` and workers with `dask worker ADDRESS`") from None
    try:
        n = len(client.scheduler_info().get("workers", {})) or workers
        say(f"Dask dashboard: {client.dashboard_link}  ({n} workers)")
        # task keys carry the spec's fingerprint: two campaigns on one scheduler never share a task
        tag = hashlib.sha256(spec_json.encode()).hexdigest()[:16]
        futures = {client.submit(compute_chunk, spec_json, c, pure=False, key=f"fdikit-{tag}-chunk-{c}"): c
                   for c in todo}
        for fut in as_completed(list(futures)):
            done(futures[fut], fut.result())
        return n
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_campaign(spec: CampaignSpec, out: str | Path, *, workers: int | None = None, backend: str = "local",
                 scheduler: str | None = None, fresh: bool = False, progress: bool = False,
                 say: Callable[[str], None] | None = None) -> CampaignRun:
    """Run (or resume) a campaign into a results folder.

    Parameters
    ----------
    spec : CampaignSpec
        From :func:`fdikit.campaign.spec.load_campaign`.
    out : str or Path
        Results folder (:mod:`fdikit.campaign.store`).
    workers : int, optional
        Worker processes (default: the machine's CPU count); with a ``scheduler``, the cluster's own.
    backend : {'local', 'dask'}
        Process pool or Dask distributed; a ``scheduler`` implies ``'dask'``.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``).
    fresh : bool
        Replace results of another spec in ``out``.
    progress : bool
        A rich progress bar with the runs done and the time remaining.
    say : callable, optional
        Where messages go (the Dask dashboard address); default ``print`` when ``progress``.

    Returns
    -------
    CampaignRun

    Raises
    ------
    ParameterError
        For a bad backend or worker count, an unreachable scheduler, or ``out`` holding another campaign.

    Examples
    --------
    A script that starts worker processes guards its entry point (the workers import the main module):

    >>> from fdikit.campaign.spec import load_campaign
    >>> if __name__ == "__main__":  # doctest: +SKIP
    ...     done = run_campaign(load_campaign("path-linear"), "out/campaign/path-linear", workers=2, progress=True)
    ...     print(done.computed, done.reused, f"{done.seconds:.0f} s")
    """
    import os

    from fdikit.campaign.plan import plan_runs
    from fdikit.campaign.store import CampaignStore

    if backend not in BACKENDS:
        raise ParameterError(f"backend (--backend) must be one of {BACKENDS}, got {backend!r}")
    if scheduler is not None:
        backend = "dask"
    if workers is None:
        workers = os.cpu_count() or 1
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ParameterError(f"workers (--workers) must be a whole number >= 1, got {workers!r}")
    say = say or (print if progress else (lambda _msg: None))
    t0 = time.perf_counter()
    plan = plan_runs(spec)
    n_chunks = plan[-1].chunk + 1
    store = CampaignStore(out, spec, runs=len(plan), chunks=n_chunks, fresh=fresh)
    reused = store.done_chunks()
    todo = [c for c in range(n_chunks) if c not in reused]
    sizes = {c: min(spec.chunk_size, len(plan) - c * spec.chunk_size) for c in range(n_chunks)}
    spec_json = spec.model_dump_json()
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeElapsedColumn, TimeRemainingColumn

    bar = Progress("[progress.description]{task.description}", BarColumn(), MofNCompleteColumn(),
                   TimeElapsedColumn(), "ETA", TimeRemainingColumn(), disable=not progress)
    with bar:
        task = bar.add_task(f"campaign {spec.name}: runs", total=len(plan),
                            completed=sum(sizes[c] for c in reused))

        def done(chunk: int, data: bytes) -> None:
            store.write_chunk(chunk, data)
            bar.update(task, advance=sizes[chunk])

        used = workers
        if todo:
            if backend == "local":
                _local(spec_json, todo, min(workers, len(todo)), done, say)
            else:
                used = _dask(spec_json, todo, workers, scheduler, done, say)
    store.finish()
    return CampaignRun(store.folder, len(plan), n_chunks, len(todo), len(reused), time.perf_counter() - t0,
                       used, backend)


def replay(folder: str | Path, run: int, design: str, evaluator: str):
    """Recompute one run of a finished campaign: ``(trace, residuals, diagnosis)``.

    Parameters
    ----------
    folder : str or Path
        The results folder (its manifest holds the spec).
    run : int
        The run index.
    design, evaluator : str
        Names from the spec.

    Returns
    -------
    tuple
        The study's :meth:`~fdikit.campaign.studies.Study.replay`.

    Raises
    ------
    ParameterError
        For an unknown run, design or evaluator.

    Examples
    --------
    >>> folder = "out/campaign/path-linear"
    >>> trace, residuals, diagnosis = replay(folder, 17, "beard-jones", "threshold")  # doctest: +SKIP
    >>> diagnosis.first_alarm()  # doctest: +SKIP
    """
    from fdikit.campaign.plan import plan_run
    from fdikit.campaign.spec import spec_fingerprint
    from fdikit.campaign.store import read_manifest

    spec = CampaignSpec.model_validate(read_manifest(folder)["spec"])
    for what, name, names in (("design", design, [d.name for d in spec.designs]),
                              ("evaluator", evaluator, [e.name for e in spec.evaluators])):
        if name not in names:
            raise ParameterError(f"{what} {name!r} is not in the campaign; choose from: {', '.join(names)}")
    study, setup = _setup(spec, spec_fingerprint(spec))
    return study.replay(setup, spec, plan_run(spec, run), design, evaluator)

