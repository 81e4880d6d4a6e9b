"""The ``doodle`` command line.

Every command reports bad input as one line ``doodle: error: …`` naming the file (and line,
track or field) and exits non-zero; set ``DOODLE_DEBUG=1`` to see a traceback instead.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from pathlib import Path

from doodle.core.errors import DoodleError

EXIT_BAD_INPUT = 1
EXIT_USAGE = 2


def _segmenter_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("segmenter")
    g.add_argument("--calibration", metavar="FILE", help="TOML from `doodle calibrate` (thresholds, mounts)")
    g.add_argument("--eps", type=float, help="stillness threshold, m/s (default 0.05)")
    g.add_argument("--theta", type=float, help="translation if |v| >= theta*|w|, m/rad (default 0.3)")
    g.add_argument("--smoothing", choices=["laplacian", "savgol"], help="denoising filter (default laplacian)")
    g.add_argument("--max-gap", type=float, help="seconds of lost tracking repaired by interpolation (default 0.5)")


def _input_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--convention", choices=["unity", "openvr", "doodle"], help="coordinate convention of CSV input")
    p.add_argument("--columns", metavar="MAP", help="CSV column map, e.g. t=time,c0.px=x,c0.py=y,…")
    p.add_argument("--tracks", metavar="NAMES", help="comma-separated track names (default: all)")


def _params(args):
    from dataclasses import replace

    from doodle.input.segmenter import SegmenterParams
    from doodle.input.settings import read_calibration

    params, mounts = SegmenterParams(), {}
    if args.calibration:
        params, mounts = read_calibration(args.calibration, params)
    given = {k: getattr(args, a) for k, a in (("eps", "eps"), ("theta", "theta"), ("smoothing", "smoothing"),
                                             ("max_gap", "max_gap")) if getattr(args, a) is not None}
    return replace(params, **given), mounts


def _load(path, args, mounts, raw=False):
    from doodle.input.csvimport import parse_column_map
    from doodle.input.loader import load

    columns = parse_column_map(args.columns) if args.columns else None
    tracks = [t.strip() for t in args.tracks.split(",") if t.strip()] if args.tracks else None
    return load(path, args.convention, columns, tracks, mounts, raw)


def _each_file(args, mounts, work) -> int:
    """``work(path, doodle)`` for every input file; a bad file is reported in one line and
    the others still run; non-zero exit status if any failed."""
    failed = 0
    for path in args.files:
        try:
            work(path, _load(path, args, mounts))
        except DoodleError as e:
            _error(e)
            failed += 1
    return EXIT_BAD_INPUT if failed else 0


def _seconds(doodle):
    """Sample index → seconds from the first sample (an end index past the last sample
    gives the last sample's time); ``doodle`` may also be an array of sample times."""
    t = doodle.t if hasattr(doodle, "t") else doodle
    last = len(t) - 1
    return lambda i: round(float(t[min(i, last)] - t[0]), 6)


def cmd_tokens(args) -> int:
    from doodle.input.segmenter import tokenize_doodle

    params, mounts = _params(args)

    def work(path, doodle):
        tokens = tokenize_doodle(doodle, params)
        seconds = _seconds(doodle)
        if args.json:
            tracks = {name: [{"token": k.name, "start": seconds(k.start), "end": seconds(k.end),
                              "samples": [k.start, k.end]} for k in toks] for name, toks in tokens.items()}
            print(json.dumps({"file": str(path), "tracks": tracks}), flush=True)
            return
        print(f"{path}  ({len(doodle.tracks)} track{'s' * (len(doodle.tracks) != 1)}, "
              f"{doodle.t[-1]:.2f} s at {doodle.rate:g} Hz, device {doodle.device})")
        for name, toks in tokens.items():
            print(f"  {name}: {' '.join(k.name for k in toks) or '(no tokens)'}")
            if args.verbose:
                for k in toks:
                    print(f"    {seconds(k.start):8.3f} {seconds(k.end):8.3f}  {k.name}")

    return _each_file(args, mounts, work)


def _library_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--library", metavar="DIR", help="a user library (folder with library.toml)")
    p.add_argument("--no-builtin", action="store_true", help="use only the library given with --library")


def cmd_recognize(args) -> int:
    from grammar.recognizer import load_actions, recognize

    params, mounts = _params(args)
    compiled = load_actions(args.library, not args.no_builtin)

    def work(path, doodle):
        result = recognize(doodle, compiled, params, args.threshold, args.direction_costs)
        seconds = _seconds(doodle)
        if args.json:
            segments = [
                {"track": name, "action": s.action, "start": seconds(s.start), "end": seconds(s.end),
                 "exact": s.exact, "distance": s.distance, "interaction": getattr(s, "interaction", None),
                 **({"refused": s.refused, "reason": s.reason} if getattr(s, "refused", "") else {}),
                 "samples": [s.start, s.end], "tokens": [k.name for k in toks[s.first:s.stop]]}
                for name, (toks, segs) in result.items() for s in segs
            ]
            print(json.dumps({"file": str(path), "segments": segments}), flush=True)
            return
        n = len(compiled.library.actions)
        print(f"{path}  ({doodle.t[-1]:.2f} s, {n} action{'s' if n != 1 else ''} in the library)")
        for name, (toks, segs) in result.items():
            print(f"  {name}: {', '.join(_named(s) for s in segs) or '(nothing)'}")
            if args.verbose:
                for s in segs:
                    how = "exact" if s.exact else ("no match" if s.action == "unknown" else f"distance {s.distance:g}")
                    if getattr(s, "refused", ""):
                        how = f"refused {s.refused} ({s.reason})"
                    print(f"    {seconds(s.start):8.3f} {seconds(s.end):8.3f}  {s.action:<16} {how:<12} "
                          f"{' '.join(k.name for k in toks[s.first:s.stop])}")

    return _each_file(args, mounts, work)


def _named(segment) -> str:
    """An action, with the interaction it plays a role in (or why it was refused)."""
    inter = getattr(segment, "interaction", None)
    if getattr(segment, "refused", ""):
        return f"unknown (refused {segment.refused}: {segment.reason})"
    return f"{segment.action} [{inter}, role {segment.role}]" if inter else segment.action


def cmd_compile(args) -> int:
    from doodle.core.files import atomic_write
    from doodle.app.pipeline import compile_doodle, quality
    from retarget.bvh import write_bvh

    from retarget.terrain import parse_terrain

    params, mounts = _params(args)
    terrain = parse_terrain(args.terrain) if args.terrain else None
    doodle = _load(args.file, args, mounts)
    from doodle.app.pipeline import read_edits

    qualities = read_edits(args.edits) if args.edits else {}
    for name, value in (("--time", args.time), ("--weight", args.weight)):
        if not -1.0 <= value <= 1.0:
            raise DoodleError(f"{name} must be between -1 and 1, not {value:g}")
    for name, value in (("--fps", args.fps), ("--scale", args.scale if args.scale is not None else 1.0)):
        if not (value > 0 and value < float("inf")):
            raise DoodleError(f"{name} must be a positive number, not {value:g}")
    if not args.threshold >= 0:
        raise DoodleError(f"--threshold must be 0 or more, not {args.threshold:g}")
    if args.time or args.weight:
        qualities.setdefault((None, None), (args.time, args.weight))
    effort_model = None
    if not args.no_effort:
        from laban.models import load as load_effort_model

        effort_model = load_effort_model(args.effort_model)
    results = compile_doodle(doodle, args.library, not args.no_builtin, params, args.fps, args.scale, args.threshold,
                             not args.no_foot_pinning, terrain, args.jump_arc, args.retime, qualities, args.style,
                             effort_model, progress_bar("segments"))
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    report = {"file": str(args.file), "fps": args.fps,
              "duration_s": round(float(results[0].sample_times[-1] - results[0].sample_times[0]), 6),
              "terrain": args.terrain or "flat", "tracks": {}}
    for r in results:
        seconds = _seconds(r.sample_times)  # the compiled timeline (placement may insert walks)
        bvh = out / f"{r.track}.bvh"
        write_bvh(bvh, r.motion)
        report["tracks"][r.track] = {
            "bvh": str(bvh), "frames": r.motion.frames,
            "segments": [{"index": i, "action": s.action, "start": seconds(s.start), "end": seconds(s.end),
                          "exact": s.exact, "distance": s.distance, "clip": r.clips.get(s.action),
                          "interaction": getattr(s, "interaction", None), "role": getattr(s, "role", None),
                          "time": r.styles[i][0], "weight": r.styles[i][1], "effort": _effort_entry(r.efforts[i]),
                          "tokens": [k.name for k in r.tokens[s.first:s.stop]]} for i, s in enumerate(r.segments)],
            "transitions": [round(b, 6) for b in r.transitions],
            "metrics": quality(r),
        }
    if args.preview:
        from retarget.preview import keyframes, plan_view

        from doodle.app.cli.render import preview_sheet

        report["preview"] = [str(plan_view(results, {r.track: r.projected for r in results}, out / "plan.png")),
                             str(keyframes(results, out / "keyframes.png"))]
        sheet = preview_sheet(results, terrain, out / "render.png", args.fps)
        if sheet is not None:
            report["preview"].append(str(sheet))
    atomic_write(out / "report.json", [json.dumps(report, indent=2) + "\n"])
    for name, tr in report["tracks"].items():
        m = tr["metrics"]
        print(f"{tr['bvh']}: {tr['frames']} frames at {args.fps:g} fps; "
              f"{', '.join(s['action'] for s in tr['segments'])}")
        print(f"  foot skating {m['foot_skating_m_per_s']} m/s, ground penetration {m['ground_penetration_m']} m, "
              f"root deviation {m['root_deviation_m']} m, transition smoothness {m['transition_smoothness']}")
    print(f"{out / 'report.json'}" + (f"; preview: {', '.join(report['preview'])}" if args.preview else ""))
    return 0


def show_progress(stage: str, i: int, n: int) -> None:
    """Draw (or redraw) the progress bar of ``stage`` on stderr: ``i`` of ``n`` done."""
    done = int(24 * i / max(n, 1))
    print(f"\r  {stage:<14} [{'#' * done}{'.' * (24 - done)}] {i}/{n}", end="" if i < n else "\n",
          file=sys.stderr, flush=True)


def progress_bar(stage: str | None = None):
    """A progress callback for long work when stderr is a terminal, else None: ``(i, n)``
    for one ``stage``, or ``(stage, i, n)`` without one."""
    if not sys.stderr.isatty():
        return None
    return show_progress if stage is None else (lambda i, n: show_progress(stage, i, n))


def _effort_entry(effort) -> dict | None:
    """What the effort model said about a segment (None: given by the user, or not asked)."""
    if effort is None:
        return None
    return {"time": effort.time, "weight": effort.weight, "p_sudden": round(effort.p_sudden, 3),
            "p_strong": round(effort.p_strong, 3), "time_confidence": round(effort.time_confidence, 3),
            "weight_confidence": round(effort.weight_confidence, 3), "drive": effort.drive, "state": effort.state}


def cmd_stylize(args) -> int:
    from retarget.analysis import Stages, guess_roles, stages
    from retarget.bvh import read_bvh_with_unit, write_bvh
    from retarget.stylize import stylize

    for name, value in (("--time", args.time), ("--weight", args.weight)):
        if not -1.0 <= value <= 1.0:
            raise DoodleError(f"{name} must be between -1 and 1, not {value:g}")
    motion, unit = read_bvh_with_unit(args.clip)
    if args.stages:
        try:
            ends = [int(x) for x in args.stages.split(",")]
        except ValueError:
            raise DoodleError(f"--stages: expected four frame numbers like 8,16,24,32, not {args.stages!r}") from None
        if len(ends) != 4 or ends != sorted(ends) or ends[-1] > motion.frames:
            raise DoodleError(f"--stages: four increasing frame numbers within the clip's {motion.frames} frames")
        found = Stages(*ends, motion.frames)
    else:
        found = stages(motion)
    if args.cyclic:
        from retarget.stylize import cyclic

        out = cyclic(motion, args.weight)
    else:
        out = stylize(motion, found, args.time, args.weight)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    write_bvh(args.output, out, unit=unit)
    print(f"{args.output}: {out.frames} frames at {out.fps:.4g} fps ({out.duration:.2f} s; neutral "
          f"{motion.duration:.2f} s), time {args.time:+g}, weight {args.weight:+g}; stages "
          f"{found.preparation},{found.anticipation},{found.execution},{found.follow_through}")
    if args.compare:
        from retarget.preview import compare_picture

        roles = guess_roles(motion.skeleton)
        effectors = [roles[k] for k in ("right_hand", "left_hand", "right_foot", "left_foot") if k in roles]
        print(compare_picture(motion, out, effectors, args.compare, f"time {args.time:+g}, weight {args.weight:+g}"))
    return 0


def cmd_library(args) -> int:
    from grammar.recognizer import load_actions
    from grammar.library import overlaps, swallowed

    if args.library_command == "import":
        return _library_import(args)
    if args.library_command == "show":
        return _library_show(args)
    if args.library_command == "sheet":
        return _library_sheet(args)
    compiled = load_actions(args.library, not args.no_builtin)
    lib = compiled.library
    if args.library_command == "list":
        for action, dfa in zip(lib.actions, compiled.dfas):
            flags = ",".join(f for f in ("cyclic", "in_place", "jumping") if getattr(action, f)) or "-"
            print(f"{action.name:<18} {flags:<16} {action.expression}")
        return 0
    found = overlaps(compiled)
    print(f"{lib.source}: {len(lib.actions)} actions, all expressions compile; "
          f"{len(found)} overlapping pair{'s' * (len(found) != 1)}")
    for o in found:
        print(f"  {o.first} ~ {o.second}: both accept {' '.join(o.witness)}")
    taken = swallowed(compiled, least=0.05)
    if taken:
        print("typical performances read as another action (the narrower language wins an overlap):")
    for s in taken:
        print(f"  {s.winner} is read for {s.share:.0%} of {s.action}'s typical strings, e.g. {' '.join(s.witness)}")
    return 0


def _library_import(args) -> int:
    from library.manifest import load_library
    from retarget.clips import load_clips
    from retarget.importer import import_library

    output = Path(args.output or args.name)
    lib = import_library(args.folder, args.name, output, args.map, args.include)
    clips = load_clips(load_library(output))  # validates and analyses what was written
    print(f"{output / 'library.toml'}: {len(lib.actions)} actions from {sum(len(a.clips) for a in lib.actions)} clips")
    for name, found in clips.items():
        c = found[0]
        b = c.stages.bounds()
        cycle = f", cycle {c.cycle_length:.2f} m" if c.cycle_length is not None else ""
        rec = "recognisable" if lib.action(name).expression else "clip only"
        print(f"  {name:<18} {len(found)} clip(s), {c.motion.frames} frames at {c.motion.fps:.4g} fps{cycle}; "
              f"execution frames {b['execution'][0]}-{b['execution'][1]}; {rec}")
    return 0


def _library_sheet(args) -> int:
    from library.manifest import builtin, combine, load_library
    from retarget.clips import load_clips
    from retarget.preview import atomic_png
    from retarget.sheet import contact_sheet

    user = load_library(args.library) if args.library else None
    lib = combine(None if args.no_builtin else builtin(), user)
    clips = load_clips(lib)
    if not clips:
        raise DoodleError(f"{lib.source}: no action has clips to draw")
    motions = {name: found[0].motion for name, found in clips.items()}
    frames = {name: [0, *list(found[0].stages.bounds()[k][1] for k in ("preparation", "anticipation", "execution",
                                                                        "follow_through")), found[0].motion.frames - 1]
              for name, found in clips.items()}
    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_png(out, lambda name: contact_sheet(motions, name, frames=frames))
    print(f"{out}: {len(motions)} clips, key frames at the stage ends (side and front views)")
    return 0


def _library_show(args) -> int:
    from library.manifest import builtin, combine, load_library
    from retarget.clips import load_clip

    user = load_library(args.library) if args.library else None
    lib = combine(None if args.no_builtin else builtin(), user)
    action = lib.action(args.action)
    flags = ", ".join(f for f in ("cyclic", "in_place", "jumping") if getattr(action, f)) or "none"
    print(f"{action.name}  (from {action.source})\n  expression: {action.expression or '(none: clip only)'}\n  flags: {flags}")
    if action.note:
        print(f"  note: {action.note}")
    for path in action.clips:
        clip = load_clip(lib, action, path)
        stages = ", ".join(f"{k} {s}-{e}" for k, (s, e) in clip.stages.bounds().items())
        cycle = f"; cycle {clip.cycle_length:.2f} m" if clip.cycle_length is not None else ""
        print(f"  clip {path}: {clip.motion.frames} frames at {clip.motion.fps:.4g} fps{cycle}\n    stages: {stages}")
    if not action.clips:
        print("  clips: none yet")
    return 0


def cmd_import(args) -> int:
    from doodle.input.fileformat import write_doodle

    doodle = _load(args.file, args, None, raw=True)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    write_doodle(args.output, doodle, convention="doodle")
    print(f"{args.output}: {len(doodle.tracks)} track(s), {len(doodle.t)} samples, {doodle.t[-1]:.2f} s")
    return 0


def cmd_info(args) -> int:
    def work(path, doodle):
        print(f"{path}: device {doodle.device}, {doodle.rate:g} Hz nominal, {len(doodle.t)} samples, "
              f"{doodle.t[-1]:.2f} s")
        for tr in doodle.tracks:
            lost = 1.0 - tr.valid.mean()
            extra = "".join(f", {k} {v}" for k, v in (("role", tr.role), ("serial", tr.serial)) if v)
            print(f"  {tr.name}{extra}: lost tracking {lost:.1%} of samples")

    return _each_file(args, {}, work)


def cmd_calibrate(args) -> int:
    from doodle.input.calibration import calibrate
    from doodle.input.devices import calibrate_mount
    from doodle.input.settings import write_calibration

    params, mounts = _params(args)
    if args.forward:
        doodle = _load(args.forward, args, None, raw=True)
        for tr in doodle.tracks:
            mounts[tr.name] = calibrate_mount(tr)
    gestures = [args.translation, args.rotation, args.slow]
    if any(gestures):
        if not all(gestures):
            raise DoodleError("calibrate: --translation, --rotation and --slow go together")
        first = [_load(g, args, mounts) for g in gestures]
        params = calibrate(*(d.tracks[0] for d in first), first[0].rate, params)
    if not args.forward and not any(gestures):
        raise DoodleError("calibrate: give --forward FILE and/or --translation, --rotation and --slow")
    write_calibration(args.output, params, mounts)
    print(f"{args.output}: eps {params.eps:.4g} m/s, theta {params.theta:.4g} m/rad"
          + "".join(f", mount {n} {tuple(round(x, 4) for x in q)}" for n, q in mounts.items()))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="doodle", description="Spatial motion doodles: VR controller motion to character animation.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("tokens", help="print the motion tokens of doodle or CSV files")
    p.add_argument("files", nargs="+", metavar="FILE")
    _input_options(p)
    p.add_argument("--json", action="store_true", help="one JSON object per file per line")
    p.add_argument("-v", "--verbose", action="store_true", help="also list each token's time range")
    _segmenter_options(p)
    p.set_defaults(run=cmd_tokens)

    p = sub.add_parser("recognize", help="recognise actions in doodle or CSV files")
    p.add_argument("files", nargs="+", metavar="FILE")
    _input_options(p)
    _library_options(p)
    p.add_argument("--json", action="store_true", help="one JSON object per file per line")
    p.add_argument("-v", "--verbose", action="store_true", help="list each segment with its time range and tokens")
    p.add_argument("--threshold", type=float, default=2.0, help="edit-distance threshold of approximate matches (default 2)")
    p.add_argument("--direction-costs", action="store_true", help="substitutions between near directions cost less")
    _segmenter_options(p)
    p.set_defaults(run=cmd_recognize)

    p = sub.add_parser("compile", help="compile a doodle into BVH animation (one file per track) and report.json")
    p.add_argument("file", metavar="FILE")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR")
    _input_options(p)
    _library_options(p)
    p.add_argument("--fps", type=float, default=30.0, help="output frame rate (default 30)")
    p.add_argument("--scale", type=float, help="doodle-to-world scale (default 8.5: a 20 cm prop, a 1.7 m character)")
    p.add_argument("--threshold", type=float, default=2.0, help="edit-distance threshold of approximate matches")
    p.add_argument("--terrain", metavar="SPEC", help="flat[:H], jacksboro[:SIZE], s1045[:SIZE], "
                   "heightfield:FILE.npz[:SPACING] or mesh:FILE.obj|ply|glb (default flat)")
    p.add_argument("--no-foot-pinning", action="store_true", help="leave feet as the blended clips put them")
    p.add_argument("--jump-arc", choices=["clip", "hermite", "apex"], default="clip",
                   help="jump height from the clip (default), a Hermite arc (alpha 2.5), or one keeping the doodle's apex")
    p.add_argument("--preview", action="store_true", help="also draw plan.png (paths) and keyframes.png (poses)")
    p.add_argument("--time", type=float, default=0.0, help="Laban Time for every segment: sustained -1 … sudden 1")
    p.add_argument("--weight", type=float, default=0.0, help="Laban Weight for every segment: light -1 … strong 1")
    p.add_argument("--edits", metavar="FILE.json", help="per-segment time and weight (see README)")
    p.add_argument("--effort-model", metavar="MODEL.npz",
                   help="Laban Effort model for segments without a given quality (default: the shipped one)")
    p.add_argument("--no-effort", action="store_true", help="do not recognise Time and Weight: neutral unless given")
    p.add_argument("--style", choices=["modifiers", "preferred"], default="modifiers",
                   help="Laban as the thesis's Time/Weight modifiers, or its study's preferred combination "
                        "(gesture retiming + motion scale + reshaping)")
    p.add_argument("--retime", choices=["uniform", "gesture"], default="uniform",
                   help="one-shot clips at an even pace (default) or following the hand's own timing (5.3.3)")
    _segmenter_options(p)
    p.set_defaults(run=cmd_compile)

    p = sub.add_parser("stylize", help="apply Laban Time and Weight to a BVH clip")
    p.add_argument("clip", metavar="CLIP.bvh")
    p.add_argument("--time", type=float, default=0.0, help="L_t in [-1, 1]: sustained < 0 < sudden")
    p.add_argument("--weight", type=float, default=0.0, help="L_w in [-1, 1]: light < 0 < strong")
    p.add_argument("--stages", metavar="P,A,E,F", help="frames ending preparation, anticipation, execution, "
                   "follow-through (default: extracted)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh")
    p.add_argument("--compare", metavar="PNG", help="neutral and stylised side by side, with end-effector paths")
    p.add_argument("--cyclic", action="store_true",
                   help="a cycle (a walk): Weight as upper-body swing and posture only, no retiming; Time ignored")
    p.set_defaults(run=cmd_stylize)

    p = sub.add_parser("library", help="action libraries: list, show, check, sheet, import")
    lsub = p.add_subparsers(dest="library_command", required=True, metavar="list|show|check|sheet|import")
    for cmd, text in (("list", "every action with its flags and expression"),
                      ("check", "compile every expression and report overlapping actions")):
        q = lsub.add_parser(cmd, help=text)
        _library_options(q)
        q.set_defaults(run=cmd_library)
    q = lsub.add_parser("show", help="one action: expression, flags, clips with their stages")
    q.add_argument("action")
    _library_options(q)
    q.set_defaults(run=cmd_library)
    q = lsub.add_parser("sheet", help="contact sheet PNG: each action's clip at its stage ends")
    q.add_argument("-o", "--output", default="out/library_sheet.png", metavar="PNG")
    _library_options(q)
    q.set_defaults(run=cmd_library)
    q = lsub.add_parser("import", help="build a library from a folder of BVH clips")
    q.add_argument("folder", metavar="DIR")
    q.add_argument("--name", required=True, help="the library's name")
    q.add_argument("--map", metavar="FILE", help="TOML rules naming actions from file names")
    q.add_argument("--include", default="*.bvh", metavar="GLOB", help="only files matching (default *.bvh)")
    q.add_argument("-o", "--output", metavar="OUT", help="library folder to write (default: ./NAME)")
    q.set_defaults(run=cmd_library)

    from doodle.app.cli import laban as cli_laban, learn as cli_learn, record as cli_record, render as cli_render, replay as cli_replay

    cli_record.add_record_parser(sub)
    cli_render.add_parser(sub)
    cli_laban.add_parser(sub)
    cli_learn.add_parser(sub, _input_options, _segmenter_options)
    cli_replay.add_parser(sub, _input_options, _segmenter_options)

    p = sub.add_parser("import", help="convert a CSV recording into a doodle file")
    p.add_argument("file", metavar="CSV")
    p.add_argument("-o", "--output", required=True, metavar="FILE.doodle")
    _input_options(p)
    p.set_defaults(run=cmd_import)

    p = sub.add_parser("info", help="describe doodle files: device, rate, tracks, lost tracking")
    p.add_argument("files", nargs="+", metavar="FILE")
    _input_options(p)
    p.set_defaults(run=cmd_info)

    p = sub.add_parser("calibrate", help="measure a prop's forward and the Segmenter's thresholds")
    p.add_argument("-o", "--output", required=True, metavar="FILE.toml")
    p.add_argument("--forward", metavar="FILE", help="hold the prop still facing forward, then push it forward")
    p.add_argument("--translation", metavar="FILE", help="a minimal translation-only gesture")
    p.add_argument("--rotation", metavar="FILE", help="a minimal rotation-only gesture")
    p.add_argument("--slow", metavar="FILE", help="your slowest deliberate motion")
    _input_options(p)
    _segmenter_options(p)
    p.set_defaults(run=cmd_calibrate)
    return parser


def _error(e: BaseException) -> None:
    print(f"doodle: error: {e}", file=sys.stderr, flush=True)


def _warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"doodle: warning: {message}", file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    warnings.showwarning = _warning
    try:
        if getattr(args, "no_builtin", False) and not getattr(args, "library", None):
            raise DoodleError("--no-builtin needs --library DIR")
        return args.run(args)
    except DoodleError as e:
        _error(e)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("doodle: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as e:  # a bug, not bad input: one line unless debugging
        if os.environ.get("DOODLE_DEBUG"):
            raise
        print(f"doodle: internal error: {type(e).__name__}: {e} (set DOODLE_DEBUG=1 for a traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
