"""Contexter cost: interactions recognised across 2 and 4 tracks, per frame of
the doodle, beside the per-track recognition it runs after (Segmenter + Matcher, batch); and
streamed as `doodle replay` runs it (the live Contexter), CPU time per frame, beside replay
without it (and the wall-clock p99, which a shared machine inflates)."""

import time

import numpy as np

from bench.timing import best_of, cpu_per_frame
from grammar.recognizer import load_actions, recognize, track_automata
from doodle.app.replay import replay
from doodle.synth.strokes import stroke, synth_doodle
from grammar.contexter import InteractionSegment, with_interactions

FACING, BACK = (0.0, 0.0, 0.0, 1.0), (0.0, 1.0, 0.0, 0.0)


def scene(tracks: int, repeats: int = 10):
    """Pairs of characters 0.3 m apart, facing each other: the slapper steps back and
    forward (the thesis's Slap) while the other keeps still, then bobs, ``repeats`` times."""
    one = [stroke("T_STILL", 0.5), stroke("T_N_Z", 0.3), stroke("T_Z", 0.3), stroke("T_STILL", 0.4)]
    still = [stroke("T_STILL", 1.1), stroke("T_Y", 0.2), stroke("T_N_Y", 0.2)]
    strokes, starts, facing = {}, {}, {}
    for k in range(tracks):
        name = f"c{k}"
        strokes[name] = (one if k % 2 == 0 else still) * repeats + [stroke("T_STILL", 0.5)]
        starts[name] = (2.0 * (k // 2), 1.0, 0.3 * (k % 2))
        facing[name] = FACING if k % 2 == 0 else BACK
    return synth_doodle(strokes, rate=90, seed=4, start_p=starts, start_q=facing)


def main() -> None:
    from dataclasses import replace

    from grammar.library import compile_library

    compiled = load_actions()
    without = compile_library(replace(compiled.library, interactions=()))  # the Contexter left out
    print("Contexter (interactions across tracks; thesis Slap scene repeated)")
    for tracks in (2, 4):
        doodle = scene(tracks)
        start = time.perf_counter()
        recognised = recognize(doodle, compiled, interactions=False)
        base = time.perf_counter() - start
        best = best_of(lambda: with_interactions(doodle, compiled, recognised))
        result = with_interactions(doodle, compiled, recognised)
        frames = len(doodle.t)
        found = sum(1 for segs in result.values() for s in segs if isinstance(s, InteractionSegment)) // 2
        print(f"  {tracks} tracks, {doodle.t[-1]:.0f} s ({frames} frames): {found} interactions; "
              f"Contexter {best / frames * 1e6:.1f} µs per frame   (baseline, per-track recognition "
              f"{base / frames * 1e6:.1f} µs per frame)")
        automata = track_automata(compiled, doodle.names)
        alone = cpu_per_frame(doodle, without, automata=automata)
        live = cpu_per_frame(doodle, compiled, automata=automata)
        wall = replay(doodle, compiled, automata=automata).costs
        print(f"    streamed (doodle replay, live Contexter), CPU per frame: p50 {np.percentile(live, 50) * 1e3:.3f} ms, "
              f"p99 {np.percentile(live, 99) * 1e3:.2f} ms, max {live.max() * 1e3:.2f} ms   (without it: p99 "
              f"{np.percentile(alone, 99) * 1e3:.2f} ms; target p99 ≤ 1 ms); wall-clock p99 "
              f"{np.percentile(wall, 99) * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
