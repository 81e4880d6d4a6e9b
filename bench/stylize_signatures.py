"""Time and Weight signatures on real motion capture (thesis §5.4.3, Figs. 5.13–5.16).

For each clip and each style (Time ±1, Weight ±1): the measures of
:mod:`retarget.effort_signature` on the clip's most moving hand or foot, neutral → styled,
whether the style shows its signature (every measure the right way, no joint faster than
:data:`~retarget.effort_signature.FASTEST`), the share of time a flat foot slides
(``retarget.qa.check``, neutral vs styled, both at the styled clip's 120 fps:
``retarget.stylize.sliding_share``) and the pops (joints > 15 m/s between frames).

Held out: the nine Bandai dataset-1 ``*_normal_001`` one-shots the issue named (bow, bye,
byebye, call, guide, kick, punch, respond, slash) — no constant was chosen on them. Tuning
clips (``--tuning``): Bandai dataset-1 ``call/punch/slash_normal_002`` and dataset-2's
raise-up and wave clips. Also prints the fastest hands and feet of the real clips (the
calibration of the speed bound).

Then the four Time × Weight States together (:func:`combined`): in how many clips each
Factor still shows its signature with the other applied — Time against the neutral clip and
against Weight alone, Weight against Time alone — on the held-out clips, the tuning clips
(with ``--tuning``) and ten other one-shots (:data:`OTHER`) that no choice was made on; and
every built-in one-shot in eight styles through the animation check (:func:`built_ins`: pops,
feet sliding more than neutral).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from retarget.analysis import guess_roles, stages
from retarget.bvh import read_bvh
from retarget.effort_signature import FASTEST, SIGNATURES, THESIS, quality, shows, signature
from retarget.qa import check
from retarget.stylize import sliding_share, stylize

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap"
BANDAI = MOCAP / "bandai"
HELD_OUT = ("bow", "bye", "byebye", "call", "guide", "kick", "punch", "respond", "slash")
TUNING = ("dataset-1/dataset-1_call_normal_002", "dataset-1/dataset-1_punch_normal_002",
          "dataset-1/dataset-1_slash_normal_002", "dataset-2/dataset-2_raise-up-both-hands_normal_001",
          "dataset-2/dataset-2_raise-up-right-hand_normal_002", "dataset-2/dataset-2_wave-both-hands_normal_001",
          "dataset-2/dataset-2_wave-right-hand_normal_002")
STYLES = ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0))


# One-shots in neither set, read only by the Time × Weight table (:func:`combined`): the
# dataset-2 takes the tuning set left out and DeepMimic's strikes and jump (another skeleton).
OTHER = ("bandai/dataset-2/dataset-2_raise-up-left-hand_normal_001", "bandai/dataset-2/dataset-2_raise-up-left-hand_normal_002",
         "bandai/dataset-2/dataset-2_raise-up-both-hands_normal_002", "bandai/dataset-2/dataset-2_raise-up-right-hand_normal_001",
         "bandai/dataset-2/dataset-2_wave-both-hands_normal_002", "bandai/dataset-2/dataset-2_wave-right-hand_normal_001",
         "deepmimic/punch", "deepmimic/kick", "deepmimic/spinkick", "deepmimic/jump")


def other_paths() -> list[Path]:
    return [MOCAP / f"{c}.bvh" for c in OTHER]


def held_out_paths() -> list[Path]:
    return [BANDAI / "dataset-1" / f"dataset-1_{c}_normal_001.bvh" for c in HELD_OUT]


def tuning_paths() -> list[Path]:
    return [BANDAI / f"{c}.bvh" for c in TUNING]


def evaluate(motion, lt: float, lw: float) -> dict:
    """One clip, one style: neutral and styled measures, signature shown, feet, pops."""
    neutral = signature(motion)
    styled_motion = stylize(motion, stages(motion), lt, lw)
    styled = signature(styled_motion, neutral.effector)
    c = check(styled_motion)
    name = quality(lt, lw)
    return {"quality": name, "neutral": neutral, "styled": styled, "shows": shows(neutral, styled, name),
            "slide_neutral": sliding_share(motion, styled_motion.frame_time),
            "slide_styled": len(c.sliding) / styled_motion.frames,
            "pops": len(c.pops)}


def row(clip: str, r: dict) -> str:
    n, s = r["neutral"], r["styled"]
    keys = SIGNATURES[r["quality"]]
    cells = []
    for k, unit in (("peak_speed", "m/s"), ("execution", "s"), ("extent", "m"), ("sharpness", "m/s²")):
        mark = "*" if k in keys else " "
        cells.append(f"{mark}{getattr(n, k):5.2f}→{getattr(s, k):5.2f}")
    return (f"  {clip:<28} {r['quality']:<9} " + " ".join(cells) + f"  {s.fastest:5.1f}"
            f"  {'yes' if r['shows'] else 'NO ':<4} {100 * r['slide_neutral']:4.1f}%→{100 * r['slide_styled']:4.1f}%"
            f"  {r['pops']}")


def table(paths: list[Path], title: str) -> tuple[int, int]:
    print(title)
    print(f"  {'clip':<28} {'quality':<9} {'peak m/s':>12} {'execution s':>12} {'extent m':>12} "
          f"{'sharp m/s²':>12} {'fast':>5}  sig  slide n→s     pops")
    shown = total = 0
    for path in paths:
        if not path.exists():
            continue
        motion = read_bvh(path)
        clip = path.stem.replace("_normal", "").replace("dataset-", "d")
        for lt, lw in STYLES:
            r = evaluate(motion, lt, lw)
            print(row(clip, r))
            shown += r["shows"] and r["pops"] == 0 and r["slide_styled"] <= r["slide_neutral"] + 1e-9
            total += 1
    print(f"  signature shown with feet and pops kept: {shown} of {total}")
    return shown, total


COMBINED = ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0))


def combined(paths: list[Path], title: str) -> None:
    """The four Time × Weight States: does each Factor still show its signature
    (:func:`~retarget.effort_signature.shows`) with the other applied — Time against the
    neutral clip and against Weight alone, Weight against Time alone (Laban's Factors are
    independent: a Sudden Light is as Sudden as a Sudden Strong)? Counts of clips, with pops
    and feet sliding more than neutral."""
    counts = {s: [0, 0, 0, 0] for s in COMBINED}
    clips = 0
    for path in paths:
        if not path.exists():
            continue
        motion = read_bvh(path)
        st = stages(motion)
        neutral = signature(motion)
        alone = {k: signature(stylize(motion, st, *k), neutral.effector) for k in STYLES}
        clips += 1
        for lt, lw in COMBINED:
            out = stylize(motion, st, lt, lw)
            s = signature(out, neutral.effector)
            c = counts[lt, lw]
            c[0] += shows(neutral, s, quality(lt, 0.0))
            c[1] += shows(alone[0.0, lw], s, quality(lt, 0.0))
            c[2] += shows(alone[lt, 0.0], s, quality(0.0, lw))
            q = check(out)
            c[3] += bool(q.pops) or len(q.sliding) / out.frames > sliding_share(motion, out.frame_time) + 1e-9
    print(f"{title}: Time × Weight together, clips of {clips} where each Factor shows its signature")
    print(f"  {'State':<18} {'Time vs neutral':>16} {'Time vs Weight alone':>21} {'Weight vs Time alone':>21}"
          f" {'pops or feet worse':>19}")
    for (lt, lw), c in counts.items():
        name = f"{'Sudden' if lt > 0 else 'Sustained'} {'Strong' if lw > 0 else 'Light'}"
        print(f"  {name:<18} {c[0]:>16} {c[1]:>21} {c[2]:>21} {c[3]:>19}")
    print(f"  all three checks: {sum(sum(c[:3]) for c in counts.values())} of {3 * len(COMBINED) * clips}")


EIGHT = STYLES + COMBINED


def built_ins() -> None:
    """Every built-in one-shot in the eight Time / Weight styles through the animation check
    (what ``doodle compile`` plays): how many pop, how many slide a flat foot more than the
    neutral clip does, and how many fail the check otherwise (a foot held still in the air, a
    flight hanging, sinking), naming them. The library's cyclic actions are styled as cycles
    and left out."""
    from library.manifest import builtin
    from retarget.clips import load_clips

    popped, slid, failed, total = [], [], [], 0
    cycles = {a.name for a in builtin().actions if a.cyclic}  # styled as cycles (Weight's swing), not here
    for name, clips in load_clips(builtin()).items():
        if name in cycles:
            continue
        clip = clips[0]
        for lt, lw in EIGHT:
            out = stylize(clip.motion, clip.stages, lt, lw)
            q = check(out)
            total += 1
            label = f"{name} {quality(lt, lw) if lt == 0 or lw == 0 else f'{lt:+g}/{lw:+g}'}"
            if q.pops:
                popped.append(f"{label} ({len(q.pops)})")
            more = len(q.sliding) / out.frames - sliding_share(clip.motion, out.frame_time)
            if not q.passes and not q.pops and not len(q.sliding):
                failed.append(f"{label} ({'hovering' if len(q.hovering) else 'sinking' if len(q.sinking) else 'other'})")
            if more > 1e-9:
                slid.append(f"{label} (+{100 * more:.1f} %)")
    print(f"Built-in one-shots, 8 styles each (Time or Weight ±1, and the four States as time/weight): {total} styled")
    print(f"  with pops: {len(popped)}" + (f" — {', '.join(popped)}" if popped else ""))
    print(f"  a flat foot sliding more than neutral: {len(slid)}" + (f" — {', '.join(slid)}" if slid else ""))
    print(f"  failing the animation check otherwise (feet held up in the air or hanging, sinking): {len(failed)}"
          + (f" — {', '.join(failed)}" if failed else ""))


def fastest_real() -> None:
    """The fastest hands and feet (joints, between frames) of the real clips: the bound's calibration."""
    best = {}
    for path in sorted(BANDAI.glob("dataset-*/*.bvh")) + sorted((MOCAP / "deepmimic").glob("*.bvh")):
        m = read_bvh(path)
        from retarget.skeleton import forward_kinematics

        w = forward_kinematics(m)[0]
        roles = guess_roles(m.skeleton)
        ends = [roles[k] for k in ("right_hand", "left_hand", "right_foot", "left_foot") if k in roles]
        v = float((np.linalg.norm(np.diff(w[:, ends], axis=0), axis=2) / m.frame_time).max())
        best[path.parent.name + "/" + path.stem] = v
    top = sorted(best.items(), key=lambda kv: -kv[1])[:3]
    print("Fastest real hands/feet: " + ", ".join(f"{k} {v:.1f} m/s" for k, v in top)
          + f"; the bound FASTEST = {FASTEST:g} m/s")


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    if not BANDAI.exists():
        print(f"Stylisation signatures: no motion capture under {BANDAI} (skipped)")
        return
    print("Stylisation signatures (thesis Figs. 5.13–5.16), most moving hand or foot, neutral → styled")
    for name, text in THESIS.items():
        print(f"  thesis, {name:<9}: {text}; measured: "
              + ", ".join(f"{k} {'up' if d > 0 else 'down'}" for k, d in SIGNATURES[name].items()))
    print("  (* the measures of the style's signature; fast: the styled clip's fastest joint, m/s)")
    if "--tuning" in argv or "--tuning-only" in argv:
        table(tuning_paths(), "Tuning clips (constants chosen on these)")
        combined(tuning_paths(), "Tuning clips")
    if "--tuning-only" not in argv:
        table(held_out_paths(), "Held out: Bandai dataset-1 *_normal_001")
        combined(held_out_paths(), "Held out")
        combined(other_paths(), "Other one-shots (Bandai dataset-2, DeepMimic)")
        built_ins()
    if "--calibrate" in argv:
        fastest_real()


if __name__ == "__main__":
    main()
