"""``doodle recognize``: the actions in doodle or CSV files (the one Recognizer)."""

from __future__ import annotations

import json

from doodle.app.cli.options import each_file, input_options, library_options, segmenter_options, segmenter_params


def add_arguments(p) -> None:
    """The arguments of ``doodle recognize``."""
    p.add_argument("files", nargs="+", metavar="FILE")
    input_options(p)
    library_options(p)
    p.add_argument("--json", action="store_true", help="one JSON object per file per line")
    p.add_argument("-v", "--verbose", action="store_true", help="list each segment with its time range and tokens")
    p.add_argument("--threshold", type=float, default=2.0, help="edit-distance threshold of approximate matches (default 2)")
    p.add_argument("--direction-costs", action="store_true", help="substitutions between near directions cost less")
    segmenter_options(p)
    p.set_defaults(run=cmd_recognize)


def cmd_recognize(args) -> int:
    from doodle.app.report import recognized, seconds_of
    from grammar.contexter import Refused
    from doodle.app.libcache import compiled_actions as load_actions
    from grammar.recognizer import recognize

    params, mounts = segmenter_params(args)
    compiled = load_actions(args.library, not args.no_builtin)

    def work(path, doodle):
        result = recognize(doodle, compiled, params, args.threshold, args.direction_costs)
        seconds = seconds_of(doodle)
        if args.json:
            print(json.dumps(recognized(path, doodle, result)), flush=True)
            return
        n = len(compiled.library.actions)
        print(f"{path}  ({doodle.t[-1]:.2f} s, {n} action{'s' if n != 1 else ''} in the library)")
        for name, (toks, segs) in result.items():
            print(f"  {name}: {', '.join(_named(s) for s in segs) or '(nothing)'}")
            if args.verbose:
                for s in segs:
                    how = "exact" if s.exact else ("no match" if s.action == "unknown" else f"distance {s.distance:g}")
                    if isinstance(s, Refused):
                        how = f"refused {s.refused} ({s.reason})"
                    print(f"    {seconds(s.start):8.3f} {seconds(s.end):8.3f}  {s.action:<16} {how:<12} "
                          f"{' '.join(k.name for k in toks[s.first:s.stop])}")

    return each_file(args, mounts, work)


def _named(segment) -> str:
    """An action, with the interaction it plays a role in (or why it was refused)."""
    from grammar.contexter import InteractionSegment, Refused

    if isinstance(segment, Refused):
        return f"unknown (refused {segment.refused}: {segment.reason})"
    if isinstance(segment, InteractionSegment):
        return f"{segment.action} [{segment.interaction}, role {segment.role}]"
    return segment.action
