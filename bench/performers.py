"""Recognition across performers: the built-in library read on a grid of performer styles.

Scenes come from :mod:`doodle.performers` — gestures played as continuous movements, not the
token-per-stroke performer the recogniser was built around — over the style grid
(:func:`doodle.performers.style_grid`: size ×0.5–×2, tempo ×0.6–×1.6, pauses 0–0.8 s, 60–144
Hz, prop tilted 10–20° in the hand, wobble 2–5°, jitter 0.3–1 mm, walks bobbed 4–10 mm per
step, jump arcs from "up, over, down" to "forward through the top", and three performers
combining several). A scene is read *exactly* when ``doodle recognize``'s actions, Idle left
out, are the intended ones, Idle left out (no unknown, nothing extra).

Printed: the main example (thesis Fig. 4.7) per style over 3 takes; every built-in action
alone (Idle, action, Idle) and inside a sequence (Idle, Walk, action, Side Walk Left, Idle)
over 2 takes per style; the most common misreadings; and, beside them in the same run, the
same scenes read by the Segmenter without its deliberate-motion stage (no levelling, no
holds or blips absorbed — the tokens as they were before). Draws ``out/bench/performers.png``
(style × action, coloured by the exact rate). ``python -m bench.performers [--quick]``.
"""

from __future__ import annotations

import sys
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

from doodle.performers import GESTURES, MAIN_EXAMPLE, perform, style_grid
from doodle.pipeline import load_actions, recognize
from doodle.segmenter import SegmenterParams

RAW = SegmenterParams(pause_s=0.0, significance=0.0, min_extent_s=0.0, level_cap=0.0)
ACTIONS = [a for a in GESTURES if a != "Idle"]
OUT = Path("out/bench/performers.png")


def reading(compiled, actions, style, seed, params=SegmenterParams()) -> tuple[bool, str]:
    doodle, _ = perform(actions, style, seed)
    segments = recognize(doodle, compiled, params)["c0"][1]
    got = [s.action for s in segments if s.action != "Idle"]
    return got == [a for a in actions if a != "Idle"], " ".join(got)


def rate(values) -> float:
    return float(np.mean(values)) if len(values) else float("nan")


def main(quick: bool = False) -> dict:
    compiled = load_actions()
    styles = style_grid()
    takes_main, takes_action = (2, 1) if quick else (3, 2)
    print("Recognition across performer styles (doodle.performers; exact = the intended actions, Idle aside)")
    main_ok, main_raw, misread = defaultdict(list), defaultdict(list), Counter()
    for style in styles:
        for take in range(takes_main):
            ok, got = reading(compiled, MAIN_EXAMPLE, style, take)
            main_ok[style.label()].append(ok)
            main_raw[style.label()].append(reading(compiled, MAIN_EXAMPLE, style, take, RAW)[0])
            if not ok:
                misread[("main example", got)] += 1
    all_main = [v for vs in main_ok.values() for v in vs]
    all_raw = [v for vs in main_raw.values() for v in vs]
    print(f"  main example (Fig. 4.7), {len(styles)} styles × {takes_main} takes: exact {rate(all_main):.3f} "
          f"(target ≥ 0.95); tokens without the deliberate-motion stage: {rate(all_raw):.3f}")
    width = max(len(k) for k in main_ok)
    for label, values in main_ok.items():
        print(f"    {label:<{width}}  {rate(values):.2f}   (without: {rate(main_raw[label]):.2f})")
    alone, inside, alone_raw = defaultdict(list), defaultdict(list), defaultdict(list)
    grid = np.zeros((len(styles), len(ACTIONS)))
    for i, style in enumerate(styles):
        for j, action in enumerate(ACTIONS):
            cell = []
            for take in range(takes_action):
                ok, got = reading(compiled, ("Idle", action, "Idle"), style, 100 + take)
                alone[action].append(ok)
                cell.append(ok)
                if not ok:
                    misread[(action, got)] += 1
                alone_raw[action].append(reading(compiled, ("Idle", action, "Idle"), style, 100 + take, RAW)[0])
                ok2, got2 = reading(compiled, ("Idle", "Walk", action, "Side Walk Left", "Idle"), style, 200 + take)
                inside[action].append(ok2)
                if not ok2:
                    misread[(f"Walk, {action}, Side Walk Left", got2)] += 1
            grid[i, j] = rate(cell)
    every = [v for vs in alone.values() for v in vs]
    print(f"  every built-in action alone ({len(styles)} styles × {takes_action} takes): exact {rate(every):.3f} "
          f"(target ≥ 0.90 each); without the stage: {rate([v for vs in alone_raw.values() for v in vs]):.3f}")
    print(f"  inside a sequence (Idle, Walk, action, Side Walk Left, Idle): exact "
          f"{rate([v for vs in inside.values() for v in vs]):.3f}")
    for action in ACTIONS:
        print(f"    {action:<16} alone {rate(alone[action]):.2f} (without: {rate(alone_raw[action]):.2f})"
              f"   in a sequence {rate(inside[action]):.2f}")
    style_rates = {s.label(): rate(list(grid[i]) + main_ok[s.label()]) for i, s in enumerate(styles)}
    worst = min(style_rates, key=style_rates.get)
    print(f"  worst style (main example and actions alone together): {worst} {style_rates[worst]:.2f} (target ≥ 0.80)")
    print("  most common misreadings:")
    for (what, got), n in misread.most_common(8):
        print(f"    ×{n}  {what} → {got or '(nothing)'}")
    _draw(grid, styles)
    print(f"  picture: {OUT}")
    return {"main": rate(all_main), "alone": {a: rate(v) for a, v in alone.items()}, "worst": style_rates[worst]}


def _draw(grid: np.ndarray, styles) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(14, 0.28 * len(styles) + 2.5))
    image = ax.imshow(grid, cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
    ax.set_xticks(range(len(ACTIONS)), ACTIONS, rotation=60, ha="right", fontsize=8)
    ax.set_yticks(range(len(styles)), [s.label() for s in styles], fontsize=7)
    ax.set_title("Built-in actions performed alone: exact rate per performer style")
    fig.colorbar(image, ax=ax, fraction=0.02)
    fig.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
