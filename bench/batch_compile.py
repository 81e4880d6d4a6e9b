"""Batch compiles on Dask (``doodle compile FOLDER``) beside the same files compiled one
after another in one process.

16 copies of examples/demo.doodle (8.6 s, 11 segments, 259 frames each), compiled:

* one after another in one Python process — ``doodle compile FILE -o OUT/STEM`` for each
  file, through :func:`doodle.app.cli.main.main`, in a child process;
* as one batch on a local cluster of 2 worker processes (:func:`doodle.app.batch.run`).

Two comparisons, each the median of ``--runs`` runs (3), taken in turns so that both sides
see the same load, each beside the target ≥ 1.8× on 2 cores:

* **end to end** — wall time of a fresh process, what a user waits for: ``doodle compile
  FOLDER -o OUT --workers 2`` (Dask's import, the cluster's start and stop, and every
  worker's own first compile — imports, the library loaded — included) against the child
  compiling the files in turn (its start-up and first compile included once); beside them
  the floor no engine can beat, a fresh process compiling the files on 2 processes it forks
  without Dask (:func:`pooled`), and what the batch replaces for a user, one ``doodle
  compile FILE`` process per file in turn (each paying its own start-up);
* **steady state** — the same 16 compiles once everything is loaded: in turn, after one
  warm-up compile in that process, against a batch sent to a running 2-worker cluster
  whose workers have each compiled once (``--scheduler`` path), set up as a local one
  (:func:`doodle.app.batch.local_config`: its housekeeping slowed, glibc's malloc untouched).

Each timed process is a fresh one started after ``os.sync()`` (the previous run's 100-odd MB
of output written out before, not by the kernel during, the next run: the batch always
followed the one-by-one run and paid for its writes), with Python's bytecode cache on as in
an installed program (a private ``PYTHONPYCACHEPREFIX``, filled untimed first, as
:mod:`bench.startup` does). OpenBLAS is pinned to one thread everywhere (``OPENBLAS_NUM_THREADS=1``, set for the child
processes and Dask's workers), so that two workers do not fight over two cores; beside the
end-to-end figures, the batch as a user's shell starts it, with no thread count set (the
batch's workers pin their BLAS themselves, :func:`doodle.app.batch.run_job`). The
machine's load average is printed before and after: other work on it takes cores from
both sides, and most from the parallel one. The batch's outputs are checked to be
byte-identical to the one-by-one ones.

``--blocks 7`` compiles copies of a 60 s doodle instead (:func:`bench.long_doodles.make_doodle`),
where the fixed costs weigh less.

Run: ``python -m bench.batch_compile [--runs N] [--files N] [--blocks N]``.
"""

from __future__ import annotations

import os

if __name__ == "__main__":  # before numpy is imported; the runs measured are child processes, pinned alike
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import contextlib
import io
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "examples" / "demo.doodle"
WORKERS = 2
TARGET = 1.8


def make_inputs(folder: Path, n: int, blocks: int = 0) -> tuple[list[Path], str]:
    """``n`` copies of the demo, or with ``blocks`` of a longer doodle of that many 8.6 s
    blocks (:func:`bench.long_doodles.make_doodle`: 7 make about a minute); and what they are."""
    folder.mkdir(parents=True, exist_ok=True)
    source, what = DEMO, f"copies of {DEMO.relative_to(ROOT)}"
    if blocks:
        from bench.long_doodles import make_doodle

        source, seconds = make_doodle(folder.parent / "long.doodle", blocks)
        what = f"copies of a {seconds:.0f} s doodle (bench.long_doodles, {blocks} blocks)"
    files = [folder / f"take{i:02d}.doodle" for i in range(1, n + 1)]
    for f in files:
        shutil.copy(source, f)
    return files, what


def one_by_one(folder: Path, out: Path, warm: bool) -> float:
    """Every doodle of ``folder`` compiled alone, in turn, in this process (output discarded);
    after one untimed compile if ``warm``. Seconds of the compiles in turn."""
    files = sorted(folder.glob("*.doodle"))
    if warm:
        with tempfile.TemporaryDirectory() as scratch:
            _compile_quietly(files[0], Path(scratch))
    start = time.perf_counter()
    for f in files:
        _compile_quietly(f, out)
    return time.perf_counter() - start


def _compile_quietly(f: Path, out: Path) -> None:
    from doodle.app.cli.main import main

    with contextlib.redirect_stdout(io.StringIO()):
        if main(["compile", str(f), "-o", str(out / f.stem)]) != 0:
            raise SystemExit(f"{f}: compile failed")


def pooled(folder: Path, out: Path) -> None:
    """The floor under the batch: every doodle of ``folder`` compiled on 2 worker processes
    forked from this one after the compile's imports — a plain ``multiprocessing`` pool, no
    Dask —, one file per task as the batch sends them."""
    import multiprocessing

    from doodle.app.cli.compile import import_compile_modules

    import_compile_modules()
    files = sorted(folder.glob("*.doodle"))
    with multiprocessing.get_context("fork").Pool(WORKERS) as pool:
        pool.starmap(_compile_quietly, [(f, out) for f in files], chunksize=1)


# what the timed children import, imported once untimed so that their bytecode is written
PRIME = ("import dask.distributed, doodle.app.cli.main, doodle.app.batch, bench.batch_compile; "
         "from doodle.app.cli.compile import import_compile_modules; import_compile_modules()")
_BYTECODE: list[Path] = []  # the children's bytecode folder (PYTHONPYCACHEPREFIX), once made


def _env(pinned: bool = True) -> dict:
    """The children's environment: OpenBLAS on one thread (unless not ``pinned``: as a user's
    shell has it, no thread count set), this checkout importable, and Python's bytecode cache
    on in a private folder (:func:`bench.startup.with_bytecode`)."""
    from bench.startup import with_bytecode

    env = dict(os.environ, OPENBLAS_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    if not pinned:
        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
            env.pop(name, None)
    return with_bytecode(env, _BYTECODE[0]) if _BYTECODE else env


def _child(argv: list[str], pinned: bool = True) -> tuple[float, str]:
    """Wall seconds of a child Python process running ``argv``, and what it printed."""
    os.sync()  # the previous run's output written out now, not by the kernel during this run
    start = time.perf_counter()
    done = subprocess.run([sys.executable, *argv], cwd=ROOT, env=_env(pinned), capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    return seconds, done.stdout


def _outputs(out: Path) -> dict:
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


def _burn(n: int = 8_000_000) -> float:
    start = time.perf_counter()
    total = 0
    for i in range(n):
        total += i
    return time.perf_counter() - start


def _load() -> str:
    """The load average, and the cores free for us: a pure-Python loop run in two processes
    at once against one alone (2.0 on an idle 2-core machine)."""
    import multiprocessing

    alone = _burn()
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        pool.map(abs, [1, 2], chunksize=1)  # both processes started
        start = time.perf_counter()
        pool.map(_burn, [8_000_000] * 2, chunksize=1)
        both = time.perf_counter() - start
    return f"load average {', '.join(f'{x:.2f}' for x in os.getloadavg())}; free cores ≈ {2 * alone / both:.2f}"


def end_to_end(takes: Path, out: Path, runs: int) -> tuple[list, list, list, list, list, bool]:
    """Seconds per run of the files compiled one after another, as one batch, on the floor's
    pool, as one batch started without OPENBLAS_NUM_THREADS (as a user's shell starts it), and
    as one ``doodle compile FILE`` process per file in turn (a shell loop: what the batch
    replaces for a user); and whether the batch's outputs equal the one-by-one ones."""
    serial, batch, pool, user, loop, same = [], [], [], [], [], True
    command = ["-m", "doodle.app.cli.main", "compile", str(takes), "-o", str(out), "--workers", str(WORKERS)]
    for _ in range(runs):
        serial.append(_child(["-m", "bench.batch_compile", "--one-by-one", str(takes), str(out)])[0])
        alone = _outputs(out)
        batch.append(_child(command)[0])
        same = same and _outputs(out) == alone  # into the same folders: report.json's paths alike
        pool.append(_child(["-m", "bench.batch_compile", "--pool", str(takes), str(out)])[0])
        user.append(_child(command, pinned=False)[0])
        loop.append(sum(_child(["-m", "doodle.app.cli.main", "compile", str(f), "-o", str(out / f.stem)])[0]
                        for f in sorted(takes.glob("*.doodle"))))
    return serial, batch, pool, user, loop, same


def steady_state(takes: Path, out: Path, runs: int) -> tuple[list, list]:
    import logging

    import dask
    from dask.distributed import LocalCluster

    from doodle.app import batch
    from doodle.app.cli.compile import compiled_counts
    from doodle.app.cli.main import build_parser

    args = build_parser().parse_args(["compile", str(takes), "-o", str(out)])
    jobs, options = batch.plan(batch.expand_inputs(args.files), out), batch.options_for_workers(args)
    serial, parallel = [], []
    with dask.config.set(batch.local_config()), \
            LocalCluster(n_workers=WORKERS, threads_per_worker=1, processes=True, dashboard_address=None,
                         silence_logs=logging.CRITICAL, env={"OPENBLAS_NUM_THREADS": "1"}) as cluster:
        warm = [batch.Job(jobs[0].file, out / ".warm" / str(i)) for i in range(WORKERS)]
        batch.run(warm, compiled_counts, options, WORKERS, cluster.scheduler_address)
        for _ in range(runs):
            serial.append(float(_child(["-m", "bench.batch_compile", "--one-by-one", str(takes), str(out),
                                        "--warm"])[1]))
            start = time.perf_counter()
            rows = batch.run(jobs, compiled_counts, options, WORKERS, cluster.scheduler_address)
            parallel.append(time.perf_counter() - start)
            if any(r.status != "ok" for r in rows):
                raise SystemExit(f"batch failed: {[r.error for r in rows if r.error]}")
    return serial, parallel


def _line(label: str, serial: list, batch: list, files: int, pool: list | None = None) -> None:
    s, b = statistics.median(serial), statistics.median(batch)
    runs = lambda xs: ", ".join(f"{x:.1f}" for x in xs)  # noqa: E731
    print(f"  {label}")
    print(f"    one after another, one process  {s:6.1f} s  ({runs(serial)})  {files / s:5.2f} files/s")
    print(f"    {WORKERS}-worker local cluster          {b:6.1f} s  ({runs(batch)})  {files / b:5.2f} files/s")
    print(f"    speed-up {s / b:.2f}×  (target ≥ {TARGET}×: {'met' if s / b >= TARGET else 'not met'})")
    if pool:
        p = statistics.median(pool)
        print(f"    floor, {WORKERS} forked processes without Dask {p:4.1f} s  ({runs(pool)}): speed-up {s / p:.2f}×")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.batch_compile")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--files", type=int, default=16)
    ap.add_argument("--blocks", type=int, default=0,
                    help="compile copies of a doodle of this many 8.6 s blocks instead of the demo (7: about 60 s)")
    ap.add_argument("--one-by-one", nargs=2, metavar=("FOLDER", "OUT"), help=argparse.SUPPRESS)
    ap.add_argument("--warm", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--pool", nargs=2, metavar=("FOLDER", "OUT"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one_by_one:
        print(f"{one_by_one(Path(args.one_by_one[0]), Path(args.one_by_one[1]), args.warm):.6f}")
        return 0
    if args.pool:
        pooled(Path(args.pool[0]), Path(args.pool[1]))
        return 0

    with tempfile.TemporaryDirectory() as tmp:
        takes, out = Path(tmp) / "takes", Path(tmp) / "out"
        _, what = make_inputs(takes, args.files, args.blocks)
        _BYTECODE[:] = [Path(tmp) / "bytecode"]
        _child(["-c", PRIME])  # bytecode written, untimed
        print(f"Batch compile: {args.files} {what}, one after another in one process vs a {WORKERS}-worker local "
              f"Dask cluster (median of {args.runs}; {os.cpu_count()} CPUs, OPENBLAS_NUM_THREADS=1)")
        print(f"  before: {_load()}")
        serial, batch, pool, user, loop, same = end_to_end(takes, out, args.runs)
        warm_serial, warm_batch = steady_state(takes, out, args.runs)
    print(f"  after:  {_load()}")
    _line("end to end (fresh processes: start-up, imports, cluster start and stop included)", serial, batch,
          args.files, pool)
    print(f"    the batch started without OPENBLAS_NUM_THREADS (a user's shell) {statistics.median(user):4.1f} s  "
          f"({', '.join(f'{x:.1f}' for x in user)})")
    print(f"    beside: one `doodle compile FILE` process per file in turn (a shell loop) {statistics.median(loop):4.1f} s  "
          f"({', '.join(f'{x:.1f}' for x in loop)}): the batch {statistics.median(loop) / statistics.median(batch):.2f}× "
          "faster (start-up paid per file; the target is read against the one-process row above)")
    _line("steady state (everything loaded; a running cluster)", warm_serial, warm_batch, args.files)
    print(f"  batch outputs byte-identical to one-by-one: {'yes' if same else 'NO'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
