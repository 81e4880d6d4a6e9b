"""``doodle library list|show|check|sheet|import``: action libraries."""

from __future__ import annotations

from pathlib import Path

from doodle.core.errors import DoodleError
from doodle.core.files import output_file
from doodle.app.cli.options import library_of, library_options


def add_arguments(p) -> None:
    """The arguments of ``doodle library``."""
    lsub = p.add_subparsers(dest="library_command", required=True, metavar="list|show|check|sheet|import")
    for cmd, text in (("list", "every action with its flags and expression"),
                      ("check", "compile every expression and report overlapping actions")):
        q = lsub.add_parser(cmd, help=text)
        library_options(q)
        q.set_defaults(run=cmd_library)
    q = lsub.add_parser("show", help="one action: expression, flags, clips with their stages")
    q.add_argument("action")
    library_options(q)
    q.set_defaults(run=cmd_library)
    q = lsub.add_parser("sheet", help="contact sheet PNG: each action's clip at its stage ends")
    q.add_argument("-o", "--output", default="out/library_sheet.png", metavar="PNG",
                   help="the picture to write (default out/library_sheet.png)")
    q.add_argument("--overwrite", action="store_true", help="replace PNG if it exists")
    library_options(q)
    q.set_defaults(run=cmd_library)
    q = lsub.add_parser("import", help="build a library from a folder of BVH clips")
    q.add_argument("folder", metavar="DIR")
    q.add_argument("--name", required=True, help="the library's name")
    q.add_argument("--map", metavar="FILE", help="TOML rules naming actions from file names")
    q.add_argument("--include", default="*.bvh", metavar="GLOB", help="only files matching (default *.bvh)")
    q.add_argument("-o", "--output", metavar="OUT", help="library folder to write (default: ./NAME): a new folder, "
                   "or a library whose manifest and clips are replaced once the import succeeds (its other files "
                   "are kept); the clips are copied into OUT/clips")
    q.set_defaults(run=cmd_library)


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
    """Every clip is read and analysed from where it is (errors name the file as the user
    knows it) before anything is written; then the library is written into a staging folder
    and swapped in whole: a failed or killed import leaves an existing library as it was."""
    from doodle.core.files import safe_file_name
    from library.folder import check_library_folder, updating
    from library.manifest import load_library, manifest_path
    from retarget.clips import load_clips
    from retarget.importer import IMPORTED, plan_library, write_library

    if args.output is None and (safe_file_name(args.name) != args.name or args.name in (".", "..")):
        raise DoodleError(f"--name {args.name!r}: not usable as a folder name; give the folder with -o OUT")
    output = check_library_folder(Path(args.output or args.name))
    lib = plan_library(args.folder, args.name, args.map, args.include, str(manifest_path(output)))
    clips = load_clips(lib)  # validates and analyses every clip
    with updating(output, IMPORTED) as stage:
        write_library(lib, stage)
        load_library(stage)  # what was written reads back
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
    from retarget.clips import load_clips
    from retarget.preview import atomic_png
    from retarget.sheet import contact_sheet

    out = output_file(args.output, args.overwrite)
    lib = library_of(args)
    clips = load_clips(lib)
    if not clips:
        raise DoodleError(f"{lib.source}: no action has clips to draw")
    motions = {name: found[0].motion for name, found in clips.items()}
    frames = {name: [0, *list(found[0].stages.bounds()[k][1] for k in ("preparation", "anticipation", "execution",
                                                                        "follow_through")), found[0].motion.frames - 1]
              for name, found in clips.items()}
    atomic_png(out, lambda name: contact_sheet(motions, name, frames=frames))
    print(f"{out}: {len(motions)} clips, key frames at the stage ends (side and front views)")
    return 0


def _library_show(args) -> int:
    from retarget.clips import load_clip

    lib = library_of(args)
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
