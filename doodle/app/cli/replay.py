"""``doodle replay FILE [--speed X]``: a recorded doodle streamed as if live (see doodle.app.replay)."""

from __future__ import annotations

import sys

from doodle.core.errors import DoodleError


def add_arguments(p) -> None:
    """The arguments of ``doodle replay``."""
    from doodle.app.cli.options import input_options, segmenter_options

    p.add_argument("file")
    p.add_argument("--speed", type=float, default=1.0, help="1 real time (default), 2 twice as fast, 0 flat out")
    p.add_argument("--library", metavar="DIR", help="a user library (folder with library.toml)")
    p.add_argument("--no-builtin", action="store_true", help="use only the library given with --library")
    p.add_argument("--threshold", type=float, default=2.0, help="edits allowed for approximate matches (default 2)")
    input_options(p)
    segmenter_options(p)
    p.set_defaults(run=cmd_replay)


def cmd_replay(args) -> int:
    import numpy as np

    from doodle.app.cli.options import load_input, segmenter_params
    from doodle.app.libcache import compiled_actions as load_actions
    from doodle.app.replay import latencies, replay

    if not (args.speed >= 0 and np.isfinite(args.speed)):
        raise DoodleError(f"--speed must be 0 (flat out) or a positive number, not {args.speed:g}")
    params, mounts = segmenter_params(args)
    doodle = load_input(args.file, args, mounts)
    compiled = load_actions(args.library, not args.no_builtin)
    pace = "flat out" if not args.speed else f"{args.speed:g}× real time"
    print(f"{args.file}: {len(doodle.tracks)} track(s), {doodle.t[-1]:.2f} s, replayed {pace}", flush=True)

    def show(r):
        how = "provisional" if not r.final else "exact" if r.exact else f"distance {r.distance:g}"
        role = f"  [{r.interaction}, role {r.role}]" if r.interaction else ""
        print(f"  {r.at:8.2f} s  {r.track}  {r.action:<16} {r.start:7.2f}–{r.end:7.2f} s  {how:<12} "
              f"latency {r.latency:.2f} s{role}", flush=True)

    replayed = replay(doodle, compiled, params, args.speed or None, show, threshold=args.threshold)
    found, costs = replayed.found, replayed.costs
    actions = [r for r in found if not r.interaction]
    together = len({(r.interaction, r.start) for r in found if r.interaction and r.role == 0})
    soon = latencies(doodle, replayed)
    after = (f"a gesture's name shown after it ends: median {np.median(soon.named):.2f} s, decided: median "
             f"{np.median(soon.final):.2f} s" if soon.final else "no gesture")
    print(f"{len(actions)} action(s){f', {together} interaction(s)' if together else ''}; {after}; "
          f"processing per frame: p50 {np.percentile(costs, 50) * 1e3:.3f} ms, p99 {np.percentile(costs, 99) * 1e3:.3f} ms",
          file=sys.stdout)
    return 0
