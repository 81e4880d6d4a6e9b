"""Many doodles compiled at once on Dask (``doodle compile`` given several files or folders).

The inputs are expanded (a folder: every ``.doodle`` and ``.csv`` file directly in it, by
name) and given one output folder each, ``OUTDIR/STEM`` (:func:`plan`: two inputs of the
same stem are refused, naming both). Each file is one task on a ``dask.distributed``
cluster — local worker processes by default, or the workers of a running scheduler — that
compiles it exactly as ``doodle compile FILE -o OUTDIR/STEM`` would and returns one
:class:`Row`: ok, or the error in one line (:func:`run_job` never raises, so a bad file
fails alone). Dask is imported only here, inside :func:`run`: a single compile never loads it.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import threading
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterator

from doodle.core.errors import DoodleError

INPUT_SUFFIXES = (".doodle", ".csv")  # what a folder given to compile contributes (any case)
CONNECT_TIMEOUT = "10s"  # to a --scheduler
# A local cluster's housekeeping slowed down or off. Its defaults sample every worker's stack
# each 10 ms (the dashboard's profile, which no one sees here), measure memory every 100 ms
# and tick every 20 ms: with two workers, the scheduler, the client and two nannies on two
# cores, that took about a fifth of the time from the compiles (16 demo copies in 3.2 s
# against 2.5 s so).
QUIET = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.admin.system-monitor.gil.enabled": False,
    "distributed.worker.memory.monitor-interval": "5s",
    "distributed.admin.tick.interval": "1s",
}
# glibc's malloc left as it is. Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 for its workers
# (in this process's environment, so every worker spawned after it, and any program this
# process starts later, inherit it): a fixed trim threshold turns glibc's adaptive mmap
# threshold off, so every large numpy array of a compile is mapped and unmapped afresh — a
# 60 s doodle compiled in 0.30 s instead of 0.25 s.
UNTRIMMED = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


@dataclass(frozen=True)
class Job:
    file: str  # the input as named (a folder's files as FOLDER/NAME)
    out: Path  # its output folder, OUTDIR/STEM


@dataclass(frozen=True)
class Row:
    """One file's outcome: ``status`` "ok" (with its tracks, frames and the tracks whose
    animation fails the check) or "error" (with a one-line ``error``); ``seconds`` the compile
    took on its worker; its warnings."""

    file: str
    status: str
    tracks: int | None = None
    frames: int | None = None
    seconds: float = 0.0
    error: str = ""
    warnings: tuple[str, ...] = ()
    failing: tuple[str, ...] = ()


# --- inputs and outputs -------------------------------------------------------------------

def folder_inputs(folder: Path) -> list[str]:
    """The doodle files directly in ``folder`` (suffixes :data:`INPUT_SUFFIXES`), by name;
    a DoodleError when there is none."""
    try:
        found = sorted(str(p) for p in folder.iterdir() if p.suffix.lower() in INPUT_SUFFIXES and p.is_file())
    except OSError as exc:
        raise DoodleError(f"{folder}: cannot read the folder: {exc.strerror or exc}") from None
    if not found:
        raise DoodleError(f"{folder}: no doodle files in this folder (looked for {', '.join(INPUT_SUFFIXES)})")
    return found


def expand_inputs(names: list[str]) -> list[str]:
    """The input files: each name as given, a folder replaced by :func:`folder_inputs`. A
    name that is no file stays, to fail in its own row ("no such file")."""
    out = []
    for name in names:
        out += folder_inputs(Path(name)) if Path(name).is_dir() else [name]
    return out


def plan(files: list[str], outdir: Path) -> list[Job]:
    """One job per file, its output ``outdir/STEM``; two files whose stems are the same (in
    any case, as on a case-insensitive disk) are refused before any work, naming both."""
    seen: dict[str, str] = {}
    for file in files:
        stem = Path(file).stem
        other = seen.get(stem.casefold())
        if other is not None:
            raise DoodleError(f"{file}: given twice" if other == file else
                              f"{other} and {file} would both be compiled into {Path(outdir) / stem}; "
                              "rename one, or compile them into different folders")
        seen[stem.casefold()] = file
    return [Job(file, Path(outdir) / Path(file).stem) for file in files]


def options_for_workers(args: argparse.Namespace) -> argparse.Namespace:
    """The command's options as the workers need them: without the inputs and the command."""
    return argparse.Namespace(**{k: v for k, v in vars(args).items() if k not in ("files", "run")})


def default_workers() -> int:
    """The CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


# --- one job, on a worker -------------------------------------------------------------------

_local = threading.local()


def _per_thread(fallback):
    """A ``warnings.showwarning`` that records into the current thread's list while a job
    runs in it (:func:`_warnings_of_this_thread`), and otherwise shows as ``fallback``."""
    def show(message, category, filename, lineno, file=None, line=None):
        caught = getattr(_local, "caught", None)
        if caught is None:
            return fallback(message, category, filename, lineno, file, line)
        caught.append(str(message))

    show.per_thread = True
    return show


@contextlib.contextmanager
def _warnings_of_this_thread() -> Iterator[list[str]]:
    """The warnings raised in this thread during the block (workers may run jobs in threads,
    so ``warnings.catch_warnings``, which swaps process-wide state, would mix them up)."""
    if not getattr(warnings.showwarning, "per_thread", False):
        warnings.showwarning = _per_thread(warnings.showwarning)
    _local.caught = []
    try:
        yield _local.caught
    finally:
        _local.caught = None


def one_line(text: str) -> str:
    return " ".join(str(text).split())


_PINNED: set[int] = set()  # the processes whose BLAS already computes on one thread


def _one_blas_thread() -> None:
    """This process's BLAS (OpenBLAS, MKL …) computes on one thread from now on: a worker is
    one of as many as there are cores, and a compile's matrices are small. Left to itself,
    OpenBLAS starts a thread per core in every worker, and those threads spin on the cores
    the other workers need: 16 demo copies on 2 workers took 2.2-2.3 s of wall time against
    1.4 s so (OPENBLAS_NUM_THREADS only acts when numpy is first imported, before the
    workers are forked)."""
    if os.getpid() not in _PINNED:
        from threadpoolctl import threadpool_limits

        threadpool_limits(limits=1, user_api="blas")
        _PINNED.add(os.getpid())


def run_job(work: Callable, job: Job, options) -> Row:
    """``work(file, out, options) -> (tracks, frames, failing tracks)`` for one job, timed,
    with this process's BLAS on one thread (:func:`_one_blas_thread`); any failure is the
    job's row ("error", its message in one line), never an exception."""
    _one_blas_thread()
    start = time.perf_counter()
    failing: tuple[str, ...] = ()
    with _warnings_of_this_thread() as caught:
        try:
            tracks, frames, failing = work(job.file, job.out, options)
            status, error = "ok", ""
        except DoodleError as e:
            status, error, tracks, frames = "error", one_line(e), None, None
        except Exception as e:  # a bug, not bad input: still one line, the other files go on
            status, error, tracks, frames = "error", one_line(f"internal error: {type(e).__name__}: {e}"), None, None
    return Row(job.file, status, tracks, frames, time.perf_counter() - start, error, tuple(dict.fromkeys(caught)),
               tuple(failing))


# --- the cluster ----------------------------------------------------------------------------

@contextlib.contextmanager
def _quiet_dask() -> Iterator[None]:
    """Dask's loggers in this process silenced for the block (its workers are told by
    ``silence_logs``)."""
    import logging

    loggers = [logging.getLogger(name) for name in ("distributed", "dask", "tornado", "bokeh")]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels):
            lg.setLevel(level)


def start_method() -> str:
    """How local workers are started: forked on Linux, so that each begins with the modules
    this process has imported (the compile's own, imported before the cluster starts: about
    a second less per batch on 2 cores than spawning workers that import Dask and the compile
    again); the platform's default elsewhere (spawn on macOS and Windows, where fork is
    unsafe or missing). The workers run only single-threaded compile code."""
    import multiprocessing

    return "fork" if sys.platform.startswith("linux") else multiprocessing.get_start_method()


def local_config() -> dict:
    """Dask's settings for a local cluster: :data:`QUIET`, :data:`UNTRIMMED`, workers started
    as :func:`start_method` says."""
    return {**QUIET, **UNTRIMMED, "distributed.worker.multiprocessing-method": start_method()}


@contextlib.contextmanager
def client_for(workers: int, scheduler: str | None):
    """A Dask client: of the running ``scheduler``, or of a local cluster of ``workers``
    processes of one thread each (numpy and Python code: processes, not threads; started as
    :func:`start_method` says), with no dashboard, no log lines and :func:`local_config`."""
    import logging

    from dask.distributed import Client, LocalCluster

    with _quiet_dask():
        if scheduler:
            try:
                client = Client(scheduler, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError, ValueError) as e:
                raise DoodleError(f"--scheduler {scheduler}: cannot connect: {one_line(e)}") from None
            with client:
                yield client
            return
        import dask

        with dask.config.set(local_config()), \
                LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                             silence_logs=logging.CRITICAL) as cluster, Client(cluster) as client:
            yield client


def run(jobs: list[Job], work: Callable, options, workers: int, scheduler: str | None = None,
        progress: Callable[[int, int], None] | None = None) -> list[Row]:
    """Every job on Dask (:func:`client_for`; at most one local worker per job), rows in the
    jobs' order; ``progress(done, total)`` as they finish. A worker lost mid-job fails
    that job's row."""
    from dask.distributed import as_completed

    rows: dict[int, Row] = {}
    with client_for(min(workers, len(jobs)), scheduler) as client:
        futures = {client.submit(run_job, work, job, options, pure=False): i for i, job in enumerate(jobs)}
        if progress:
            progress(0, len(jobs))
        for done, future in enumerate(as_completed(futures), 1):
            i = futures[future]
            try:
                rows[i] = future.result()
            except Exception as e:  # the task itself failed: its worker died, or it could not be sent
                rows[i] = Row(jobs[i].file, "error", error=one_line(f"worker failed: {type(e).__name__}: {e}"))
            if progress:
                progress(done, len(jobs))
    return [rows[i] for i in range(len(jobs))]


# --- what is printed ------------------------------------------------------------------------

def _check(r: Row) -> str:
    """A row's animation check as the table shows it."""
    if r.status != "ok":
        return "-"
    return f"FAILS {','.join(r.failing)}" if r.failing else "passes"


def table(rows: list[Row]) -> list[str]:
    """The summary table: per file its status, tracks, frames, the animation check (the
    tracks that fail it), seconds and error."""
    head = ("file", "status", "tracks", "frames", "check", "seconds", "error")
    cells = [(r.file, r.status, "-" if r.tracks is None else str(r.tracks), "-" if r.frames is None else str(r.frames),
              _check(r), f"{r.seconds:.1f}", r.error) for r in rows]
    width = [max(len(c[k]) for c in [head, *cells]) for k in range(6)]
    lines = []
    for c in [head, *cells]:
        left = f"{c[0]:<{width[0]}}  {c[1]:<{width[1]}}"
        right = f"{c[2]:>{width[2]}}  {c[3]:>{width[3]}}  {c[4]:<{width[4]}}  {c[5]:>{width[5]}}"
        lines.append(f"{left}  {right}  {c[6]}".rstrip())
    return lines


def summary(rows: list[Row], outdir) -> str:
    ok = sum(r.status == "ok" for r in rows)
    failed = len(rows) - ok
    failing = sum(bool(r.failing) for r in rows if r.status == "ok")
    return (f"{ok} of {len(rows)} file{'s' * (len(rows) != 1)} compiled, each into {Path(outdir) / 'STEM'}/"
            + (f"; {failed} failed" if failed else "")
            + (f"; {failing} fail{'s' * (failing == 1)} the animation check (`doodle qa "
               f"{Path(outdir) / 'STEM'} -v` lists the frames)" if failing else ""))


def show_warnings(rows: list[Row]) -> None:
    """The warnings of the files (on stderr, as the single compile shows them), in file order."""
    for r in rows:
        for message in r.warnings:
            print(f"doodle: warning: {message}", file=sys.stderr, flush=True)
