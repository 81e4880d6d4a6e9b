"""BVH read and write speed (retarget.bvh) beside the independent pure-Python reader bvhio.

Two clips: one Bandai Namco clip as shipped (dataset-1_walk_normal_001.bvh) and a long clip
made from it by repeating its frames 20× in memory and writing it to a temporary folder.
For each: our read and write throughput (frames/s, MB/s of BVH text) and bvhio's times in
the same run, with the ratio (bvhio time / ours). Best of 3 runs, ``time.perf_counter``.

Baselines: bvhio ``readAsBvh`` (its raw parse: per-joint local poses, the same work as
ours), ``readAsHierarchy`` (its full load, what one uses to get world positions), and
``writeBvh`` of the parsed container with 6 decimals. Our write goes through
:func:`retarget.bvh.write_bvh`, i.e. it includes the atomic temp-file + fsync + rename;
bvhio's write does not fsync.
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

from bench.timing import best_of
from retarget.bvh import read_bvh, read_bvh_with_unit, write_bvh

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap"
CLIP = MOCAP / "bandai" / "dataset-1" / "dataset-1_walk_normal_001.bvh"
REPEAT = 20
RUNS = 3


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:9.1f} ms"


def _bench(path: Path, label: str, scratch: Path, bvhio) -> None:
    motion, unit = read_bvh_with_unit(path)
    size = path.stat().st_size / 1e6
    frames = motion.frames
    print(f"{label}: {path.name} — {frames:,} frames, {len(motion.skeleton)} joints, {size:.2f} MB")

    t_read = best_of(lambda: read_bvh(path))
    out = scratch / f"ours_{path.name}"
    t_write = best_of(lambda: write_bvh(out, motion, unit=unit))
    out_size = out.stat().st_size / 1e6
    print(f"  ours  read  {_ms(t_read)}  {frames / t_read:12,.0f} frames/s  {size / t_read:7.1f} MB/s")
    print(f"  ours  write {_ms(t_write)}  {frames / t_write:12,.0f} frames/s  {out_size / t_write:7.1f} MB/s"
          f"  (atomic, fsync)")
    if bvhio is None:
        print("  bvhio: not installed — baseline unavailable (pip install bvhio==1.5.4)")
        return
    t_bvh = best_of(lambda: bvhio.readAsBvh(str(path)))
    t_hier = best_of(lambda: bvhio.readAsHierarchy(str(path)))
    container = bvhio.readAsBvh(str(path))
    theirs = scratch / f"bvhio_{path.name}"
    t_bwrite = best_of(lambda: bvhio.writeBvh(str(theirs), container, 6))
    print(f"  bvhio readAsBvh       {_ms(t_bvh)}  {frames / t_bvh:12,.0f} frames/s   ours is "
          f"{t_bvh / t_read:5.1f}× faster")
    print(f"  bvhio readAsHierarchy {_ms(t_hier)}  {frames / t_hier:12,.0f} frames/s   ours is "
          f"{t_hier / t_read:5.1f}× faster")
    print(f"  bvhio writeBvh        {_ms(t_bwrite)}  {frames / t_bwrite:12,.0f} frames/s   ours is "
          f"{t_bwrite / t_write:5.1f}× faster")


def main() -> None:
    print(f"BVH read/write speed (best of {RUNS}, time.perf_counter)")
    if not CLIP.exists():
        print(f"  clip not found: {CLIP} — skipped")
        return
    try:
        import bvhio
    except ImportError:
        bvhio = None
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        _bench(CLIP, "Bandai clip", scratch, bvhio)
        print()
        motion, unit = read_bvh_with_unit(CLIP)
        long = replace(motion, translations=np.tile(motion.translations, (REPEAT, 1, 1)),
                       rotations=np.tile(motion.rotations, (REPEAT, 1, 1)))
        long_path = scratch / f"long_{REPEAT}x_{CLIP.name}"
        write_bvh(long_path, long, unit=unit)
        _bench(long_path, f"Long clip ({REPEAT}× the Bandai clip)", scratch, bvhio)


if __name__ == "__main__":
    main()
