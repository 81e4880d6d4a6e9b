"""Recognition across performers: the built-in library read on a grid of performer styles.

Scenes come from :mod:`doodle.synth.performers` — gestures played as continuous movements, not the
token-per-stroke performer the recogniser was built around — over the style grid
(:func:`doodle.synth.performers.style_grid`: size ×0.5–×2, tempo ×0.6–×1.6, pauses 0–0.8 s, 60–144
Hz, prop tilted 10–20° in the hand, wobble 2–5°, jitter 0.3–1 mm, walks bobbed 4–10 mm per
step, jump arcs from "up, over, down" to "forward through the top", and three performers
combining several). A scene is read *exactly* when ``doodle recognize``'s actions, Idle left
out, are the intended ones, Idle left out (no unknown, nothing extra).

Printed: the main example (thesis Fig. 4.7) per style over 3 takes; every built-in action
alone (Idle, action, Idle) and inside a sequence (Idle, Walk, action, Side Walk Left, Idle)
over 2 takes per style; the most common misreadings; and, beside them in the same run, the
same scenes read by the Segmenter without its deliberate-motion stage (no levelling, no
holds or blips absorbed; the Matcher as it is now). Then the main example played the way
the recogniser was built around, one minimum-jerk stroke per token (:mod:`doodle.synth.strokes`),
over size, tempo, noise and rate. Two worker processes, BLAS on one thread. Draws ``out/bench/performers.png``
(style × action, alone and in a sequence, coloured by the exact rate). ``python -m bench.performers [--quick]``.
"""

from __future__ import annotations

import itertools
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

from doodle.synth.performers import GESTURES, MAIN_EXAMPLE, perform, perform_two, style_grid
from grammar.recognizer import load_actions, recognize
from doodle.input.segmenter import SegmenterParams

RAW = SegmenterParams(pause_s=0.0, significance=0.0, min_extent_s=0.0, level_cap=0.0)
ACTIONS = [a for a in GESTURES if a != "Idle"]
BACK_TO_BACK = 14  # built-in actions in a row in the back-to-back scenes beside a learned library
OUT = Path("out/bench/performers.png")


def reading(compiled, actions, style, seed, params=SegmenterParams()) -> tuple[bool, str]:
    doodle, _ = perform(actions, style, seed)
    segments = recognize(doodle, compiled, params)["c0"][1]
    got = [s.action for s in segments if s.action != "Idle"]
    return got == [a for a in actions if a != "Idle"], " ".join(got)


def rate(values) -> float:
    return float(np.mean(values)) if len(values) else float("nan")


_COMPILED = None


def _one_style(job) -> dict:
    """Every scene of one style (run in a worker process)."""
    global _COMPILED
    style, takes_main, takes_action = job
    if _COMPILED is None:
        _COMPILED = load_actions()
    c = _COMPILED
    out = {"main": [], "main_raw": [], "alone": {}, "alone_raw": {}, "inside": {}, "misread": Counter()}
    for take in range(takes_main):
        ok, got = reading(c, MAIN_EXAMPLE, style, take)
        out["main"].append(ok)
        out["main_raw"].append(reading(c, MAIN_EXAMPLE, style, take, RAW)[0])
        if not ok:
            out["misread"][("main example", got)] += 1
    for action in ACTIONS:
        for key in ("alone", "alone_raw", "inside"):
            out[key][action] = []
        for take in range(takes_action):
            ok, got = reading(c, ("Idle", action, "Idle"), style, 100 + take)
            out["alone"][action].append(ok)
            if not ok:
                out["misread"][(action, got)] += 1
            out["alone_raw"][action].append(reading(c, ("Idle", action, "Idle"), style, 100 + take, RAW)[0])
            ok, got = reading(c, ("Idle", "Walk", action, "Side Walk Left", "Idle"), style, 200 + take)
            out["inside"][action].append(ok)
            if not ok:
                out["misread"][(f"Walk, {action}, Side Walk Left", got)] += 1
    return out


def _demo():
    """``examples/make_demo.py`` as a module: the demo's strokes and Fig. 4.7."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_demo", Path(__file__).parents[1] / "examples" / "make_demo.py")
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    return demo


def stroke_performer(compiled) -> tuple[float, float, Counter]:
    """The main example as ``examples/make_demo.py`` plays it — one minimum-jerk stroke per
    token (:mod:`doodle.synth.strokes`) — over size × tempo × tracking noise × rate, 2 takes each:
    the exact rate, beside the Segmenter without its deliberate-motion stage."""
    from doodle.synth.strokes import synth_doodle

    demo = _demo()
    want = [a for a in demo.FIG_4_7 if a != "Idle"]
    ours, raw, misread = [], [], Counter()
    for scale, tempo, noise, rate_hz, seed in itertools.product((0.5, 1.0, 2.0), (0.6, 1.0, 1.6), (0.0003, 0.001),
                                                                 (90.0, 144.0), range(2)):
        strokes = [replace(s, duration=s.duration * tempo) for s in demo.STROKES]
        doodle = synth_doodle({"c0": strokes}, rate=rate_hz, seed=seed, scale=scale, noise=noise)
        for params, into in ((SegmenterParams(), ours), (RAW, raw)):
            got = [s.action for s in recognize(doodle, compiled, params)["c0"][1] if s.action != "Idle"]
            into.append(got == want)
            if params is not RAW and got != want:
                misread[(f"size×{scale:g} tempo×{tempo:g} noise {noise * 1000:g} mm {rate_hz:g} Hz", " ".join(got))] += 1
    return rate(ours), rate(raw), misread


def held_out(compiled) -> tuple[float, float]:
    """The stroke-per-token performer with settings not looked at while the constants of
    the deliberate-motion stage were chosen: 60/120 Hz, ±25 % stroke variation, 1 mm
    tremor, 1 cm drift, 3–4.6° wobble, tempo ×0.7/×1.4, size ×0.6/×1.7, 3 takes each."""
    from doodle.synth.strokes import synth_doodle

    demo = _demo()
    want = [a for a in demo.FIG_4_7 if a != "Idle"]
    ours, raw = [], []
    for rate_hz, wobble, tempo, scale, seed in itertools.product((60.0, 120.0), (0.05, 0.08), (0.7, 1.4), (0.6, 1.7),
                                                                  range(3)):
        strokes = [replace(s, duration=s.duration * tempo) for s in demo.STROKES]
        doodle = synth_doodle({"c0": strokes}, rate=rate_hz, seed=1000 + seed, scale=scale, vary=0.25, tremor=0.001,
                              drift=0.01, wobble=wobble)
        for params, into in ((SegmenterParams(), ours), (RAW, raw)):
            into.append([s.action for s in recognize(doodle, compiled, params)["c0"][1] if s.action != "Idle"] == want)
    return rate(ours), rate(raw)


def _beside_one(job) -> tuple[str, list, list, Counter]:
    """The scenes of :func:`beside_learned` read with one user's learned library beside the
    built-in actions, and (for one user only: the same for all) with the built-in actions
    alone (run in a worker process)."""
    import tempfile

    from bench.learning_protocol import load as load_vive, make_library

    user, scenes, also_alone = job
    data = load_vive()[user]
    with tempfile.TemporaryDirectory() as tmp:
        folder = make_library(Path(tmp) / user, {g: ds[:3] for g, ds in sorted(data.items())}, ("c0",))
        learned, alone = load_actions(folder, True), load_actions()
        names = set(data)
        beside, without, taken = [], [], Counter()
        for actions, style, seed in scenes:
            doodle, _ = perform(actions, style, seed)
            want = [a for a in actions if a != "Idle"]
            for compiled, into in ((learned, beside), (alone, without))[:2 if also_alone else 1]:
                got = [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action != "Idle"]
                into.append(got == want)
                if compiled is learned:
                    what = f"{len(want)} back to back" if len(want) == BACK_TO_BACK else " ".join(want)
                    taken.update((g, what) for g in got if g in names)
    return user, beside, without, taken


def _beside_two(job) -> tuple[str, list, list, int]:
    """Two performers of built-in actions (one per track) read with one user's gestures
    learned with both hands beside the built-in actions, and with the built-in actions
    alone: per scene and track, whether its actions were read exactly; learned names given."""
    import tempfile

    from bench.learning_protocol import load as load_vive, make_library

    user, scenes = job
    data = load_vive()[user]
    with tempfile.TemporaryDirectory() as tmp:
        folder = make_library(Path(tmp) / user, {g: ds[:3] for g, ds in sorted(data.items())}, ("c0", "c1"))
        learned, alone = load_actions(folder, True), load_actions()
        beside, without, taken = [], [], 0
        for first, second, style, seed in scenes:
            doodle = perform_two(first, second, style, seed)
            for compiled, into in ((learned, beside), (alone, without)):
                found = recognize(doodle, compiled)
                for track, want in (("c0", first), ("c1", second)):
                    got = [getattr(s, "interaction", None) or s.action for s in found[track][1]
                           if s.action not in ("Idle", "unknown")]
                    into.append(got == [a for a in want if a != "Idle"])
                    if compiled is learned:
                        taken += sum(g in data for g in got)
    return user, beside, without, taken


def two_performer_scenes() -> list[tuple]:
    """``(first actions, second actions, style, seed)``: per style, two scenes of two
    performers each playing three random built-in actions, Idle before and after."""
    rng = np.random.default_rng(11)
    return [(("Idle", *rng.choice(ACTIONS, 3), "Idle"), ("Idle", *rng.choice(ACTIONS, 3), "Idle"), style,
             900 + 10 * k + j) for k, style in enumerate(style_grid()) for j in range(2)]


def beside_two_handed(users) -> None:
    """Two characters, one per track, each performing three random built-in actions
    (Idle between, two takes per style), read with each Vive user's gestures learned with
    both hands (``--tracks c0,c1``) beside the built-in actions, against the built-in
    actions alone: a two-handed action must not take one character's action because the
    other moved at the same time."""
    scenes = two_performer_scenes()
    with ProcessPoolExecutor(max_workers=2) as pool:
        rows = list(pool.map(_beside_two, [(u, scenes) for u in users]))
    print(f"  two performers beside a two-handed library ({len(scenes)} scenes × 2 tracks of 3 built-in actions; "
          "each user's gestures learned on c0+c1): tracks read exactly, beside the built-in actions alone")
    for user, beside, without, taken in rows:
        print(f"    {user.replace('Sub_', ''):<6} {rate(beside):.3f} (alone {rate(without):.3f}); "
              f"learned names given: {taken}")


def beside_learned() -> None:
    """Built-in actions performed with a user library beside them: each of the five Vive
    users' gestures learned on c0 from ex_0..2 (``bench.learning_protocol``), the main
    example and every built-in action alone and inside a sequence, one take per style, and
    :data:`BACK_TO_BACK` random built-in actions in a row with no Idle between (four takes
    per style) — read as ``doodle recognize --library DIR`` reads them (learned and built-in
    actions together), beside the built-in actions alone on the same scenes."""
    from bench.learning_protocol import ROOT

    if not sorted(ROOT.glob("*/*/*.csv")):
        print(f"  beside a learned library: no Vive recordings under {ROOT} (skipped)")
        return
    users = sorted(p.name for p in ROOT.iterdir() if p.is_dir())
    scenes = [(MAIN_EXAMPLE, style, 300 + k) for k, style in enumerate(style_grid())]
    scenes += [(("Idle", a, "Idle"), style, 400 + k) for k, style in enumerate(style_grid()) for a in ACTIONS]
    scenes += [(("Idle", "Walk", a, "Side Walk Left", "Idle"), style, 500 + k)
               for k, style in enumerate(style_grid()) for a in ACTIONS]
    first = len(scenes)
    rng = np.random.default_rng(7)  # and BACK_TO_BACK actions in a row, no Idle between, a few takes per style
    scenes += [(("Idle", *rng.choice(ACTIONS, BACK_TO_BACK), "Idle"), style, 700 + 10 * k + j)
               for k, style in enumerate(style_grid()) for j in range(4)]
    with ProcessPoolExecutor(max_workers=2) as pool:
        rows = list(pool.map(_beside_one, [(u, scenes, k == 0) for k, u in enumerate(users)]))
    alone, alone_b2b = rate(rows[0][2][:first]), rate(rows[0][2][first:])
    print(f"  beside a learned library (each Vive user's gestures learned on c0; {first} scenes: the main example "
          f"and every action alone and in a sequence, one take per style; and {len(scenes) - first} of "
          f"{BACK_TO_BACK} actions back to back): exact per user; the built-in actions alone: {alone:.3f}, "
          f"back to back {alone_b2b:.3f}")
    for user, beside, without, taken in rows:
        common = ", ".join(f"{g} in {what} ×{n}" for (g, what), n in taken.most_common(3))
        print(f"    {user.replace('Sub_', ''):<6} {rate(beside[:first]):.3f}, back to back {rate(beside[first:]):.3f}; "
              f"learned names given: {sum(taken.values())}" + (f" ({common})" if common else ""))
    beside_two_handed(users)


def main(quick: bool = False) -> dict:
    styles = style_grid()
    takes_main, takes_action = (2, 1) if quick else (3, 2)
    print("Recognition across performer styles (doodle.synth.performers; exact = the intended actions, Idle aside)")
    with ProcessPoolExecutor(max_workers=2) as pool:
        rows = list(pool.map(_one_style, [(s, takes_main, takes_action) for s in styles]))
    misread = sum((r["misread"] for r in rows), Counter())
    all_main = [v for r in rows for v in r["main"]]
    all_raw = [v for r in rows for v in r["main_raw"]]
    print(f"  main example (Fig. 4.7), {len(styles)} styles × {takes_main} takes: exact {rate(all_main):.3f} "
          f"(target ≥ 0.95); tokens without the deliberate-motion stage: {rate(all_raw):.3f}")
    width = max(len(s.label()) for s in styles)
    for style, r in zip(styles, rows):
        print(f"    {style.label():<{width}}  {rate(r['main']):.2f}   (without: {rate(r['main_raw']):.2f})")
    grid = np.array([[rate(r["alone"][a]) for a in ACTIONS] for r in rows])
    grid_inside = np.array([[rate(r["inside"][a]) for a in ACTIONS] for r in rows])
    joined = {key: {a: [v for r in rows for v in r[key][a]] for a in ACTIONS} for key in ("alone", "alone_raw", "inside")}
    print(f"  every built-in action alone ({len(styles)} styles × {takes_action} takes): exact "
          f"{rate([v for vs in joined['alone'].values() for v in vs]):.3f} (target ≥ 0.90 each); without the stage: "
          f"{rate([v for vs in joined['alone_raw'].values() for v in vs]):.3f}")
    print(f"  inside a sequence (Idle, Walk, action, Side Walk Left, Idle): exact "
          f"{rate([v for vs in joined['inside'].values() for v in vs]):.3f}")
    for action in ACTIONS:
        print(f"    {action:<16} alone {rate(joined['alone'][action]):.2f} (without: {rate(joined['alone_raw'][action]):.2f})"
              f"   in a sequence {rate(joined['inside'][action]):.2f}")
    style_rates = {s.label(): rate(list(grid[i]) + rows[i]["main"]) for i, s in enumerate(styles)}
    worst = min(style_rates, key=style_rates.get)
    print(f"  worst style (main example and actions alone together): {worst} {style_rates[worst]:.2f} (target ≥ 0.80)")
    ours, raw, stroke_misread = stroke_performer(load_actions())
    print(f"  the main example played one stroke per token (doodle.synth.strokes, as the demo), size 0.5–2 × tempo 0.6–1.6 × "
          f"noise 0.3–1 mm × 90/144 Hz: exact {ours:.3f}; without the stage: {raw:.3f}")
    ours, raw = held_out(load_actions())
    print(f"  held out — the same performer with settings not looked at while choosing the constants (60/120 Hz, "
          f"±25 % variation, 1 mm tremor, 1 cm drift, 3–4.6° wobble): exact {ours:.3f}; without the stage: {raw:.3f}")
    if not quick:
        beside_learned()
    print("  most common misreadings:")
    for (what, got), n in (misread + stroke_misread).most_common(10):
        print(f"    ×{n}  {what} → {got or '(nothing)'}")
    _draw(grid, grid_inside, styles)
    print(f"  picture: {OUT}")
    return {"main": rate(all_main), "alone": {a: rate(v) for a, v in joined["alone"].items()},
            "worst": style_rates[worst], "strokes": ours}


def _draw(alone: np.ndarray, inside: np.ndarray, styles) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(22, 0.28 * len(styles) + 2.5), sharey=True)
    for ax, grid, title in ((axes[0], alone, "alone (Idle, action, Idle)"),
                            (axes[1], inside, "in a sequence (Idle, Walk, action, Side Walk Left, Idle)")):
        image = ax.imshow(grid, cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
        ax.set_xticks(range(len(ACTIONS)), ACTIONS, rotation=60, ha="right", fontsize=8)
        ax.set_title(f"Built-in actions {title}: exact rate per performer style", fontsize=10)
    axes[0].set_yticks(range(len(styles)), [s.label() for s in styles], fontsize=7)
    fig.colorbar(image, ax=axes, fraction=0.015)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=100, bbox_inches="tight")
    plt.close(fig)


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
