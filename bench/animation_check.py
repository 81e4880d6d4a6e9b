"""The animation check (retarget.qa) calibrated on real motion capture, then applied to
compiled scenes.

Real motion: every Bandai ``*_normal_*`` clip (walks, runs, gestures; their floor is where
their feet rest) and the DeepMimic clips, each figure beside the check's limit — real walks
must pass. Compiled: the main example with the built-in library (plain, styled with the
effort model, on the Jacksboro terrain) and, when the Bandai import is possible, with the
Bandai library; the main example, and every built-in action alone and inside a sequence,
performed by other styles; and real input nobody here made (the Vive recordings, real
people's paths as figurine doodles: :func:`real_doodles`).
``python -m bench.animation_check``.
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


def _checked(doodle, **kw):
    from doodle.app.pipeline import compile_doodle

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = compile_doodle(doodle, **kw)
    return check_scene({r.track: r.motion for r in results}, kw.get("terrain"), contacts=results[0].contacts,
                       soles={r.track: r.sole for r in results})


def performers(seeds=(3, 11)) -> None:
    """The main example performed by every style of the performer grid (size, tempo,
    pauses, rate, tilt, wobble, jitter, bobbing, jump arcs and three combinations), styled
    by the effort model as `doodle compile` does; beside it, the same with feet left as
    the blended clips put them (no contact pinning, steps or terrain fitting): the floor."""
    from doodle.synth.performers import MAIN_EXAMPLE, perform, style_grid
    from laban.models import load as load_model

    model = load_model(None)
    styles = style_grid()
    print(f"Animation check on the main example performed by {len(styles)} styles × {len(seeds)} takes "
          "(effort model on)")
    ours, floor, failures = [], [], []
    for style in styles:
        for seed in seeds:
            doodle, _ = perform(MAIN_EXAMPLE, style, seed=seed)
            c = _checked(doodle, effort_model=model)["c0"]
            ours.append(c)
            if not c.passes:
                failures.append(f"    {style.label()} (take {seed}): {c.summary()}")
            if seed == seeds[0]:
                floor.append(_checked(doodle, effort_model=model, pin=False)["c0"])
    for name, rows in (("ours", ours), ("feet not pinned (floor)", floor)):
        slide = np.array([c.sliding_per_s for c in rows])
        print(f"  {name:<24} {sum(c.passes for c in rows)}/{len(rows)} pass; sliding median {np.median(slide):.2f} "
              f"worst {slide.max():.2f} frames/s; with pops {sum(bool(c.pops) for c in rows)}, fastest joint "
              f"{max(c.fastest for c in rows):.1f} m/s; with one-frame turns {sum(bool(c.turns) for c in rows)}; "
              f"hovering {sum(bool(c.hovering) for c in rows)}")
    print("\n".join(failures))


HELD_OUT = 37  # the performers' take the figures below are read on: none of the animation fixes were designed
# on it (they were on takes 21, 33, 34 and 36)


def actions_alone(seed: int = HELD_OUT) -> None:
    """Every built-in action performed alone (Idle, the action, Idle) by every style of the
    performer grid, one take each, styled by the effort model as `doodle compile` does:
    how many fail the animation check, by action, beside the same performances not styled."""
    _actions(lambda action: ("Idle", action, "Idle"), "performed alone", seed)


def actions_inside(seed: int = HELD_OUT) -> None:
    """Every built-in action inside a sequence (Idle, Walk, the action, Side Walk Left, Idle)
    performed by every style of the performer grid, as :func:`actions_alone`: the hand-overs
    from a walk and into a side step, with the pauses a performer leaves."""
    _actions(lambda action: ("Idle", "Walk", action, "Side Walk Left", "Idle"),
             "inside a sequence (Idle, Walk, action, Side Walk Left, Idle)", seed, skip=("Walk", "Side Walk Left"))


def _actions(scene, what: str, seed: int, skip: tuple = ()) -> None:
    from collections import Counter

    from doodle.synth.performers import GESTURES, perform, style_grid
    from laban.models import load as load_model

    model = load_model(None)
    failed, plain, total = Counter(), Counter(), 0
    for style in style_grid():
        for action in GESTURES:
            if action == "Idle" or action in skip:
                continue
            doodle, _ = perform(scene(action), style, seed=seed)
            total += 1
            failed[action] += not _checked(doodle, effort_model=model)["c0"].passes
            plain[action] += not _checked(doodle)["c0"].passes
    print(f"Animation check on every built-in action {what} by {len(style_grid())} styles (take {seed})")
    for name, counts in (("styled (effort model on)", failed), ("baseline, not styled", plain)):
        print(f"  {name:<26} {total - sum(counts.values())}/{total} pass"
              + ("; failing: " + ", ".join(f"{a} {n}" for a, n in counts.most_common() if n) if any(counts.values()) else ""))


def pairs() -> None:
    """Two characters (generated two-track doodles): Slap, Kiss, and a walk-up–slap–step-back
    story, in two layouts each."""
    from scipy.spatial.transform import Rotation

    from doodle.synth.strokes import stroke, synth_doodle

    def scene(a, b, where, turn, seed):
        def strokes(words):
            return [stroke("T_STILL", 0.4)] + [stroke(w, 0.3) for w in words] + [stroke("T_STILL", 0.5)]

        return synth_doodle({"c0": strokes(a), "c1": strokes(b)}, seed=seed,
                            start_p={"c0": (0.0, 1.0, 0.0), "c1": (where[0], 1.0, where[1])},
                            start_q={"c0": (0.0, 0.0, 0.0, 1.0),
                                     "c1": tuple(Rotation.from_euler("y", turn, degrees=True).as_quat())})

    kiss, slap = ["T_N_Z", "T_Z", "T_N_Z", "T_Z"], ["T_N_Z", "T_Z"]
    story = ["T_Z", "T_Z", "T_Z", "T_STILL", "T_N_Z", "T_Z", "T_STILL", "T_N_Z", "T_N_Z"]
    scenes = {"slap": (slap, [], (0.0, 0.3), 180.0, 1), "slap, B to the side, turned": (slap, [], (-0.12, 0.25), 160.0, 3),
              "kiss": (kiss, kiss, (0.0, 0.15), 180.0, 2), "kiss, closer": (kiss, kiss, (0.02, 0.1), 175.0, 6),
              "walk up, slap, step back": (story, [], (0.0, 0.6), 180.0, 1),
              "walk up from farther, off side": (story[:1] + story, [], (0.08, 0.75), 190.0, 5)}
    print("Animation check on two-character scenes")
    for name, args in scenes.items():
        for track, c in _checked(scene(*args)).items():
            print(_row(f"{name} ({track})", c) + f"  touching {sum(len(v) for v in c.touching.values())} fr, "
                  f"contacts missed {len(c.missed)}, reaction leading {len(c.leads)} fr")


VIVE = MOCAP.parent / "vive-gestures"
FIGURINE = 8.5  # a person's path made a figurine's: the compile's default scale, undone


def _cause(result, c) -> str:
    """What a failing track fails on: pops in a jump (a flight squeezed into a short gesture),
    other pops, sliding, characters passing through each other, or something else."""
    if len(c.pops):
        f = int(c.pops[0])
        acts = {s.action for s, (a, b) in zip(result.segments, result.frame_ranges) if a <= f <= b}
        return "pops in a jump or flip" if acts & {"Jump", "Flip", "Back Flip"} else "pops elsewhere"
    if len(c.sliding):
        return "sliding"
    return "interpenetration" if "interpenetration 0 frames" not in c.summary() else "other"


def real_doodles() -> None:
    """Input nobody here made, compiled with the built-in library: every real Vive recording
    (two hand-held controllers performing whole-body gestures, each a character here: hands
    swung at several m/s), and every real person's pelvis path (Bandai, DeepMimic) made a
    figurine's (÷ 8.5, 90 Hz, held 0.8 m up); beside them, for reference, the real clips
    themselves under the same check (:func:`real`: acrobatics and studio floors fail it too)."""
    import collections

    from doodle.app.pipeline import compile_doodle
    from doodle.core.model import Doodle, Track
    from doodle.input.loader import load
    from retarget.analysis import guess_roles
    from retarget.skeleton import forward_kinematics

    def checked(doodle):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results = compile_doodle(doodle)
        checks = check_scene({r.track: r.motion for r in results}, None, contacts=results[0].contacts,
                             soles={r.track: r.sole for r in results})
        return [(r, checks[r.track]) for r in results]

    print("Animation check on real input compiled with the built-in library")
    recordings = sorted(VIVE.glob("*/*/*.csv"))
    if recordings:
        causes, tracks = collections.Counter(), 0
        for f in recordings:
            for r, c in checked(load(f, "unity")):
                tracks += 1
                if not c.passes:
                    causes[_cause(r, c)] += 1
        print(f"  Vive recordings, {len(recordings)} files: {tracks - sum(causes.values())}/{tracks} tracks pass; "
              f"failing: " + ", ".join(f"{k} {v}" for k, v in causes.most_common()))
    clips = sorted(MOCAP.glob("bandai/dataset-*/*.bvh")) + sorted(MOCAP.glob("deepmimic/*.bvh"))
    if not clips:
        print("  ../shared/data/mocap is not here: skipped")
        return
    causes, themselves = collections.Counter(), 0
    for f in clips:
        m = read_bvh(f)
        themselves += check(m).passes
        pos, rot = forward_kinematics(m)
        pelvis = guess_roles(m.skeleton).get("pelvis", 0)
        t = np.arange(m.frames) * m.frame_time
        tt = np.arange(0.0, t[-1], 1 / 90)
        p = np.stack([np.interp(tt, t, pos[:, pelvis, k]) for k in range(3)], axis=1) / FIGURINE
        p[:, 1] += 0.8
        q = rot[np.clip(np.rint(tt / m.frame_time).astype(int), 0, m.frames - 1), pelvis]
        (r, c), = checked(Doodle((Track("c0", tt, p, q, np.ones(len(tt), bool)),), 90.0))
        if not c.passes:
            causes[_cause(r, c)] += 1
    print(f"  real people's pelvis paths as figurine doodles, {len(clips)} clips: "
          f"{len(clips) - sum(causes.values())}/{len(clips)} pass"
          + (f"; failing: " + ", ".join(f"{k} {v}" for k, v in causes.most_common()) if causes else "")
          + f"  (for reference, the clips themselves: {themselves}/{len(clips)} pass)")


def main() -> None:
    real()
    print()
    real_doodles()
    print()
    compiled()
    print()
    pairs()
    print()
    performers()
    print()
    actions_alone()
    print()
    actions_inside()


if __name__ == "__main__":
    main()
