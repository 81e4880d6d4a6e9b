"""Long doodles: does per-frame work stay constant per frame at any length?

Three doodles made in a temporary folder with :mod:`doodle.synth.strokes` (seed 7, 90 Hz):
blocks of 8.6 s, the demo's strokes (examples/make_demo.py) and the same the other way
(side-step right, walk back, jump on the spot, walk back, stomp) in turn, so the figurine
stays in the tracked space — 7 blocks (about 60 s), 70 (10 min) and 420 (1 h). Each is
compiled through the command line, ``doodle compile FILE -o DIR``, in a fresh process with
a warm library cache and Python's bytecode written (one untimed compile of the demo fills
both) and BLAS pinned to one thread. For each: the wall-clock time (median of ``--runs``
processes for the 60 s doodle, one process for the longer ones unless ``--runs-long`` says
otherwise), the time per second of doodle and its ratio to the 60 s doodle's, and the peak
resident memory of the child (its own VmHWM, :data:`PEAK`; the largest of its runs).

Beside them, a floor: a fresh ``python -c "import numpy"`` plus, in this process, writing
the compiled BVH's motion block (the same frames and channels) as text with ``np.savetxt``
at 6 decimals — the least any compiler of that output does.

Targets (issue "long doodles"): the 60 s doodle ≤ 0.5 s of work above the floor; the 10 min
one at most 1.2× the 60 s one's time per doodle-second; the 1 h one ≤ 30 s and ≤ 400 MB.
Figures are printed, never asserted. ``--profile`` also runs the longest doodle once under
cProfile (in a fresh process) and prints the functions with the most cumulative time.
Run: ``python -m bench.long_doodles [--sizes 60s,10m,1h] [--runs N] [--runs-long N] [--profile]``.

Measured on a 2-core machine shared with other jobs (load ≈ 2.8), ``--runs 5 --runs-long 3``:
before the "per-frame work" changes the 60 s doodle took 1.6 s (182 MB), 10 min 107 s
(5.8 GB: an F × F matrix for the knee's nearest bent frame) and the hour failed with a
MemoryError (95 GiB asked) after 83 s; after them 1.7 s (131 MB), 9.1 s (280 MB) and 54 s
(982 MB). The outputs (BVH and report) are byte-identical.

Issue "Speed that scales" (same machine, load ≈ 1–2, ``--runs 3 --runs-long 3``): before,
60 s 1.96 s (131 MB), 10 min 7.58 s (278 MB), 1 h 47.3 s (984 MB); after — one stylised clip
per distinct (clip, quality), foot pinning and the check reading only the joints they need,
whole-timeline arrays changed in place and worked out in blocks of frames — 1.40 s (128 MB),
5.14 s (225 MB), 26.3 s (470 MB). BVH and report.json byte-identical to before for the demo,
the 60 s and the 1 h doodle (and the 60 s one on ``--terrain jacksboro``).
"""

from __future__ import annotations

import argparse
import importlib.util
import io
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "examples" / "demo.doodle"
SIZES = {"60s": 7, "10m": 70, "1h": 420}  # repeats of the demo's 8.6 s of strokes
TARGET_60S_WORK = 0.5  # s above the floor
TARGET_RATIO_10M = 1.2  # time per doodle-second, 10 min / 60 s
TARGET_1H_S = 30.0
TARGET_1H_MB = 400.0


def back_strokes():
    """The demo's strokes the other way (8.6 s): side-steps right, walks back, jumps on the
    spot, walks back, stomps — so a long doodle made of both comes back where it started
    instead of walking out of the tracked space (±100 m)."""
    from doodle.synth.strokes import stroke

    return [stroke("T_STILL", 0.8), stroke("T_N_X", 1.2, 0.12), stroke("T_STILL", 0.5),
            stroke("T_N_Z", 1.5, 0.18), stroke("T_STILL", 0.5), stroke("T_Y", 0.5, 0.08),
            stroke("T_N_Y", 0.5, 0.08), stroke("T_STILL", 0.5), stroke("T_N_Z", 1.2, 0.14),
            stroke("T_STILL", 0.5), stroke("T_Y", 0.3, 0.06), stroke("T_N_Y", 0.25, 0.06), stroke("T_STILL", 0.8)]


def make_doodle(path: Path, repeats: int, seed: int = 7) -> tuple[Path, float]:
    """The demo's strokes and :func:`back_strokes` in turn, ``repeats`` blocks of 8.6 s,
    written to ``path``; (path, seconds)."""
    spec = importlib.util.spec_from_file_location("make_demo", ROOT / "examples" / "make_demo.py")
    make_demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_demo)
    from doodle.input.fileformat import write_doodle
    from doodle.synth.strokes import synth_doodle

    blocks = [make_demo.STROKES, back_strokes()]
    strokes = [s for k in range(repeats) for s in blocks[k % 2]]
    doodle = synth_doodle({"c0": strokes}, rate=90.0, seed=seed, device="vive-controller")
    write_doodle(path, doodle, convention="openvr")
    return path, float(doodle.t[-1] - doodle.t[0])


def _env(cache: Path, bytecode: Path) -> dict:
    """The children's environment: BLAS on one thread, the library cache in ``cache``,
    Python's bytecode written to and read from ``bytecode`` (as an installed program has it,
    even where the shell sets ``PYTHONDONTWRITEBYTECODE``)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    env.pop("DOODLE_NO_CACHE", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    env["PYTHONPYCACHEPREFIX"] = str(bytecode)
    env["DOODLE_CACHE"] = str(cache)
    return env


# Run a module as ``python -m`` does, then write the process's own peak resident memory to
# stderr as it exits. Linux's ru_maxrss of a child (os.wait4) is at least the parent's resident
# size when it forked — exec keeps that high-water mark —, so a child of a large process (this
# bench inside ``python -m bench``, grown to 2 GB by the benchmarks before it) read 2 GB for a
# 60 s doodle; /proc/self/status's VmHWM is the exec'd program's own.
PEAK = """import atexit, runpy, sys
def _peak():
    try:
        with open("/proc/self/status") as f:
            kb = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
        sys.stderr.write(f"\\nPEAK_KB {kb}\\n")
    except (OSError, StopIteration, ValueError):
        pass
atexit.register(_peak)
sys.argv = sys.argv[1:]
runpy.run_module(sys.argv[0], run_name="__main__", alter_sys=True)
"""


def run_child(argv: list[str], env: dict) -> tuple[float, float]:
    """Wall seconds and peak RSS (MB) of one fresh process running ``argv`` — a
    ``[python, "-m", MODULE, ...]`` one reports its own peak (:data:`PEAK`); any other, or
    where /proc is missing, the ``ru_maxrss`` of ``os.wait4``."""
    if argv[1:2] == ["-m"]:
        argv = [argv[0], "-c", PEAK, *argv[2:]]
    start = time.perf_counter()
    with tempfile.TemporaryFile() as err:
        child = subprocess.Popen(argv, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        lines = err.read().decode(errors="replace").strip().splitlines()
        peak = [int(line.split()[1]) for line in lines if line.startswith("PEAK_KB ")]
        if child.returncode != 0:
            said = [line for line in lines if line.strip() and not line.startswith("PEAK_KB ")] or [""]
            raise RuntimeError(f"exit status {child.returncode}: {said[-1][-300:]}")
    return wall, (peak[-1] if peak else usage.ru_maxrss) / 1024.0  # KB on Linux


def _motion_shape(bvh: Path) -> tuple[int, int]:
    """(frames, channels) of a written BVH."""
    with open(bvh) as f:
        channels = 0
        for line in f:
            words = line.split()
            if words and words[0] == "CHANNELS":
                channels += int(words[1])
            elif words and words[0] == "Frames:":
                return int(words[1]), channels
    raise ValueError(f"{bvh}: no Frames: line")


def text_floor(frames: int, channels: int) -> float:
    """Seconds to write a (frames, channels) motion block as text at 6 decimals (np.savetxt)."""
    data = np.random.default_rng(0).normal(size=(frames, channels)) * 50.0
    start = time.perf_counter()
    np.savetxt(io.StringIO(), data, fmt="%.6f")
    return time.perf_counter() - start


def profile(doodle: Path, out: Path, env: dict, top: int = 40) -> None:
    """The compile of ``doodle`` under cProfile (fresh process), its top functions printed."""
    stats = out.with_suffix(".prof")
    subprocess.run([sys.executable, "-m", "cProfile", "-o", str(stats), "-m", "doodle.app.cli.main", "compile",
                    str(doodle), "-o", str(out)], env=env, cwd=ROOT, stdout=subprocess.DEVNULL, check=True)
    import pstats

    buffer = io.StringIO()
    pstats.Stats(str(stats), stream=buffer).sort_stats("cumulative").print_stats(top)
    print(buffer.getvalue())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m bench.long_doodles", description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="60s,10m,1h", help="comma-separated from 60s,10m,1h")
    parser.add_argument("--runs", type=int, default=3, help="processes for the 60 s doodle (median; default 3)")
    parser.add_argument("--runs-long", type=int, default=1, help="processes for the longer ones (default 1)")
    parser.add_argument("--profile", action="store_true", help="cProfile the longest doodle once")
    args = parser.parse_args(argv)
    sizes = [s for s in args.sizes.split(",") if s]
    py = sys.executable
    cli = [py, "-m", "doodle.app.cli.main", "compile"]
    print("Long doodles compiled through the CLI (fresh processes, warm library cache, BLAS on one thread)")
    with tempfile.TemporaryDirectory(prefix="doodle-long-") as tmp:
        tmp = Path(tmp)
        env = _env(tmp / "cache", tmp / "bytecode")
        run_child(cli + [str(DEMO), "-o", str(tmp / "demo")], env)  # caches and bytecode filled, untimed
        startup = statistics.median(run_child([py, "-c", "import numpy"], env)[0] for _ in range(3))
        rows = {}
        for name in sizes:
            doodle, seconds = make_doodle(tmp / f"{name}.doodle", SIZES[name])
            out = tmp / f"out-{name}"
            runs = args.runs if name == "60s" else args.runs_long
            try:
                results = [run_child(cli + [str(doodle), "-o", str(out)], env) for _ in range(runs)]
            except RuntimeError as e:  # (an earlier version ran out of memory on the hour)
                print(f"  {name:>4} ({seconds:7.1f} s): failed — {e}", flush=True)
                continue
            wall = statistics.median(r[0] for r in results)
            rss = max(r[1] for r in results)
            frames, channels = _motion_shape(out / "c0.bvh")
            floor = startup + text_floor(frames, channels)
            rows[name] = (seconds, wall, rss, floor, frames)
            print(f"  {name:>4} ({seconds:7.1f} s, {frames:6d} frames): {wall:7.2f} s wall "
                  f"({1000 * wall / seconds:6.2f} ms per doodle-s), peak RSS {rss:7.1f} MB; "
                  f"floor {floor:5.2f} s", flush=True)
        print()
        if "60s" in rows:
            seconds, wall, _, floor, _ = rows["60s"]
            work = wall - floor
            print(f"  60 s: {work:.2f} s of work above the floor; target ≤ {TARGET_60S_WORK:.2f} s: "
                  f"{'met' if work <= TARGET_60S_WORK else 'missed'}")
        if "60s" in rows and "10m" in rows:
            ratio = (rows["10m"][1] / rows["10m"][0]) / (rows["60s"][1] / rows["60s"][0])
            print(f"  10 min: {ratio:.2f}× the 60 s doodle's time per doodle-second; target ≤ {TARGET_RATIO_10M}: "
                  f"{'met' if ratio <= TARGET_RATIO_10M else 'missed'}")
        if "1h" in rows:
            _, wall, rss, _, _ = rows["1h"]
            print(f"  1 h: {wall:.1f} s (target ≤ {TARGET_1H_S:.0f} s: {'met' if wall <= TARGET_1H_S else 'missed'}), "
                  f"{rss:.0f} MB peak (target ≤ {TARGET_1H_MB:.0f} MB: {'met' if rss <= TARGET_1H_MB else 'missed'})")
        if args.profile and sizes:
            name = sizes[-1]
            print(f"\ncProfile of the {name} compile (cumulative time):")
            profile(tmp / f"{name}.doodle", tmp / f"prof-{name}", env)


if __name__ == "__main__":
    main(sys.argv[1:])
