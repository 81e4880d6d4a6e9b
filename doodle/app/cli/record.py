"""``doodle record -o FILE``: record a doodle live, printing actions as they are recognised.

``--source openvr`` (default) reads the SteamVR controllers and trackers; ``--source
synthetic`` plays a built-in synthetic performance (the thesis's Fig. 4.7 scene, as in
``examples/make_demo.py``) at real speed, to try the loop without hardware.
"""

from __future__ import annotations

import math
import sys

from doodle.core.errors import DoodleError

# Thesis Fig. 4.7, as examples/make_demo.py performs it: Idle, Side Walk Left, Idle, Walk,
# Idle, Jump, Idle, Walk, Idle, Stomp, Idle.
DEMO = [("T_STILL", 0.8, None), ("T_X", 1.2, 0.12), ("T_STILL", 0.5, None), ("T_Z", 1.5, 0.18),
        ("T_STILL", 0.5, None), ("T_Y", 0.25, 0.05), ("T_Y_Z", 0.25, 0.06), ("T_N_Y_Z", 0.25, 0.06),
        ("T_N_Y", 0.25, 0.05), ("T_STILL", 0.5, None), ("T_Z", 1.2, 0.14), ("T_STILL", 0.5, None),
        ("T_Y", 0.3, 0.06), ("T_N_Y", 0.25, 0.06), ("T_STILL", 0.8, None)]


def add_arguments(p) -> None:
    """The arguments of ``doodle record``."""
    p.add_argument("-o", "--output", required=True, metavar="FILE.doodle")
    p.add_argument("--source", choices=["openvr", "synthetic"], default="openvr",
                   help="openvr: SteamVR controllers and trackers (default); synthetic: a built-in performance")
    p.add_argument("--seconds", type=float, metavar="S", help="stop after S seconds (default: Ctrl-C)")
    p.add_argument("--trigger", action="store_true", help="start at a trigger press and stop at the next")
    p.add_argument("--overwrite", action="store_true", help="replace FILE if it exists")
    p.add_argument("--library", metavar="DIR", help="a user library (folder with library.toml)")
    p.add_argument("--no-builtin", action="store_true", help="use only the library given with --library")
    p.set_defaults(run=cmd_record)


def _open_source(args):
    from doodle.input.sources import OpenVRSource, SyntheticSource
    from doodle.synth.strokes import stroke, synth_doodle

    if args.source == "openvr":
        return OpenVRSource()
    doodle = synth_doodle({"c0": [stroke(*s) for s in DEMO]}, rate=90.0, seed=7, device="synthetic")
    end = float(doodle.t[-1])
    return SyntheticSource(doodle, triggers=[0.3, end - 0.3] if args.trigger else ())


class _View:
    """The live terminal view: one line per action — first marked ``(provisional)`` as soon as
    the tokens so far say it, then again once decided — lost/found tracking, and on a
    terminal the tokens in progress on a line that keeps being rewritten."""

    def __init__(self, out=None):
        out = out or sys.stdout  # looked up now, not at import: the stream may have been replaced
        self.out, self.tty, self.pending = out, out.isatty(), {}

    def line(self, text: str) -> None:
        print(("\r\033[K" if self.tty and self.pending else "") + text, file=self.out, flush=True)
        self.status()

    def status(self) -> None:
        if self.tty and self.pending:
            print("\r\033[K  " + "   ".join(f"{k}: {v}…" for k, v in self.pending.items()), end="", file=self.out,
                  flush=True)

    def __call__(self, kind: str, e: dict) -> None:
        if kind in ("action", "provisional"):
            how = "  (provisional)" if kind == "provisional" else "" if e["exact"] else f"  (distance {e['distance']:g})"
            role = f"  [{e['interaction']}, role {e['role']}]" if "interaction" in e else ""
            self.line(f"  {e['start']:7.2f} s  {e['track']}  {e['action']}{how}{role}")
        elif kind == "refused":
            self.line(f"  {e['start']:7.2f} s  {e['track']}  {e['action']} refused: {e['reason']}")
        elif kind == "token" and not e["final"]:
            self.pending[e["track"]] = e["token"]
            self.status()
        elif kind == "lost":
            what = "tracking lost" if e["error"] is None else f"recognition restarted ({e['error']})"
            self.line(f"  {e['t']:7.2f} s  {e['track']}  {what}")
        elif kind == "found":
            self.line(f"  {e['t']:7.2f} s  {e['track']}  tracking back after {e['gap']:.2f} s")
        elif kind == "started":
            self.line(f"  recording to {e['path']}")
        elif kind == "stopped":
            self.pending = {}
            if self.tty:
                print("\r\033[K", end="", file=self.out, flush=True)


def cmd_record(args) -> int:
    from doodle.app.libcache import compiled_actions as load_actions
    from doodle.app.recorder import record
    from doodle.core.files import output_dir, output_file

    out = output_file(args.output, args.overwrite)
    if args.seconds is not None and not (args.seconds > 0 and math.isfinite(args.seconds)):
        raise DoodleError(f"--seconds must be a positive number, not {args.seconds:g}")
    source = _open_source(args)
    try:
        output_dir(out.parent if str(out.parent) else ".")
        compiled = load_actions(args.library, not args.no_builtin)
        tracks = ", ".join(f"{n} ({' '.join(x for x in (r, s) if x)})" if r or s else n for n, r, s in source.tracks)
        how = "press the trigger to start and again to stop" if args.trigger else "Ctrl-C to stop"
        print(f"{source.device}: {tracks} at {source.rate:g} Hz; {how}", flush=True)
        result = record(source, out, wait_for_trigger=args.trigger, max_seconds=args.seconds, on_event=_View(),
                        compiled=compiled, overwrite=args.overwrite)
    finally:
        source.close()
    why = {"end": "end of the source", "seconds": f"{args.seconds} s", "trigger": "trigger",
           "interrupted": "Ctrl-C"}[result.reason]
    print(f"wrote {result.path}: {result.samples} samples, {result.duration:.2f} s (stopped: {why})")
    for name, actions in result.actions.items():
        print(f"  {name}: {', '.join(a for a, _, _ in actions) or '(nothing recognised)'}")
    return 0
