"""The animation check (retarget.qa) calibrated on real motion capture, then applied to
compiled scenes.

Real motion: every Bandai ``*_normal_*`` clip (walks, runs, gestures; their floor is where
their feet rest) and the DeepMimic clips, each figure beside the check's limit — real walks
must pass. Compiled: the main example with the built-in library (plain, styled with the
effort model, on the Jacksboro terrain) and, when the Bandai import is possible, with the
Bandai library. ``python -m bench.animation_check``.
"""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path

import numpy as np

from retarget.bvh import read_bvh
from retarget.qa import Limits, check, check_scene

MOCAP = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
DEMO = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"


def _row(name, c) -> str:
    return (f"  {name:<44} slide {c.sliding_per_s:5.2f}/s  pops {len(c.pops):3d}  fastest {c.fastest:5.1f} m/s  "
            f"turns {len(c.turns):2d}  hover {len(c.hovering):3d} fr ({c.highest * 100:4.1f} cm)  sink {len(c.sinking):3d}  "
            f"{'passes' if c.passes else 'FAILS'}")


def real() -> None:
    lim = Limits()
    print(f"Animation check on real motion capture (limits: sliding ≤ {lim.slides_per_s} frames/s at "
          f"{lim.slide} m/s, joints ≤ {lim.pop} m/s, one-frame turns > {lim.turn}°, hovering > {lim.hover * 100:g} cm "
          f"for > {lim.flight} s, sinking > {lim.sink * 100:g} cm)")
    if not MOCAP.exists():
        print("  ../shared/data/mocap is not here: skipped")
        return
    groups = {"Bandai walks": [], "Bandai runs": [], "Bandai other": [], "DeepMimic": []}
    for path in sorted(MOCAP.glob("bandai/dataset-*/*_normal_*.bvh")):
        kind = "Bandai walks" if "walk" in path.stem else "Bandai runs" if "run" in path.stem else "Bandai other"
        groups[kind].append((path.stem, check(read_bvh(path))))
    for path in sorted(MOCAP.glob("deepmimic/*.bvh")):
        groups["DeepMimic"].append((path.stem, check(read_bvh(path))))
    # held out: walks in the other Bandai styles (active, angry, childish, …), not looked at while
    # the limits were chosen on the *_normal_* clips
    groups["Bandai walks, other styles (held out)"] = [
        (path.stem, check(read_bvh(path))) for path in sorted(MOCAP.glob("bandai/dataset-*/*walk*.bvh"))
        if "_normal_" not in path.stem]
    for kind, rows in groups.items():
        passed = sum(c.passes for _, c in rows)
        worst = max((c.sliding_per_s for _, c in rows), default=0.0)
        fastest = max((c.fastest for _, c in rows), default=0.0)
        print(f"  {kind}: {passed}/{len(rows)} pass; worst sliding {worst:.2f} frames/s, fastest joint {fastest:.1f} m/s")
        if kind in ("Bandai walks", "DeepMimic"):
            for name, c in rows:
                print(_row(name, c))


def compiled() -> None:
    from doodle.app.pipeline import compile_doodle
    from doodle.input.loader import load
    from laban.models import load as load_model
    from retarget.terrain import parse_terrain

    print("Animation check on compiled scenes (the main example)")
    doodle = load(DEMO)
    scenes = [("built-in, no effort", {}), ("built-in, effort model", {"effort_model": load_model(None)}),
              ("built-in, Jacksboro terrain", {"terrain": parse_terrain("jacksboro")})]
    with tempfile.TemporaryDirectory() as tmp:
        bandai = MOCAP / "bandai" / "dataset-1"
        if bandai.exists():
            from retarget.importer import import_library

            import_library(bandai, "bandai", Path(tmp) / "bandai", None, "*_normal_*")
            scenes.append(("Bandai library", {"library_dir": Path(tmp) / "bandai"}))
        for name, kw in scenes:
            with warnings.catch_warnings():  # the Bandai library's missing clips: said by compile, not here
                warnings.simplefilter("ignore")
                results = compile_doodle(doodle, **kw)
            checks = check_scene({r.track: r.motion for r in results}, kw.get("terrain"), contacts=results[0].contacts,
                                 soles={r.track: r.sole for r in results})
            for track, c in checks.items():
                print(_row(f"{name} ({track})", c))


def main() -> None:
    real()
    print()
    compiled()


if __name__ == "__main__":
    main()
