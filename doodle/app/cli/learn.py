"""``doodle learn``: teach the program a new action from a few performed examples (§4.2.5).

The action is added to a user library folder (created if missing) with the learned
expression; with two tracks (``--tracks c0,c1``) one expression is learned per track, stored
as actions ``NAME.c0`` and ``NAME.c1`` joined by an ``[[interactions]]`` entry ``NAME`` — an
expression pair performed together. The overlap check against the library then says which
actions would collide and on which token string, so the person can keep, rename or re-record.
"""

from __future__ import annotations

import time
from pathlib import Path

from doodle.core.errors import DoodleError


def add_parser(sub) -> None:
    from doodle.app.cli.options import input_options, segmenter_options

    p = sub.add_parser("learn", help="learn a new action from three (or more) performed examples")
    p.add_argument("name", help="the new action's name")
    p.add_argument("examples", nargs="*", help="doodle or CSV files, one performance each")
    p.add_argument("--library", required=True, metavar="DIR", help="user library to add it to (created if missing)")
    p.add_argument("--replace", action="store_true", help="replace an action of that name in DIR")
    p.add_argument("--no-builtin", action="store_true", help="check overlaps against DIR only")
    p.add_argument("--record", action="store_true", help="perform the examples with the controllers (needs SteamVR)")
    input_options(p)
    segmenter_options(p)
    p.set_defaults(run=cmd_learn)


TAKES = 3
COUNTDOWN = 3  # seconds before each take


def open_source():
    """The controllers (a DoodleError in one line without SteamVR)."""
    from doodle.input.sources import OpenVRSource

    return OpenVRSource()


def record_takes(name: str, folder: Path, takes: int = TAKES, sleep=time.sleep) -> list[str]:
    """The wizard: ``takes`` performances recorded with the controllers, each started and
    stopped with the trigger after a countdown, shown live; saved in ``folder/takes/``."""
    from doodle.app.cli.record import _View
    from doodle.app.recorder import record

    try:
        source = open_source()
    except DoodleError as e:
        raise DoodleError(f"{e}; or record each example elsewhere and give the files: doodle learn NAME EX1 EX2 EX3 "
                          "--library DIR") from None
    paths = []
    try:
        (folder / "takes").mkdir(parents=True, exist_ok=True)
        safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)
        for k in range(1, takes + 1):
            path = folder / "takes" / f"{safe}_{k}.doodle"
            print(f"take {k}/{takes} of {name!r}: ", end="", flush=True)
            for n in range(COUNTDOWN, 0, -1):
                print(f"{n}… ", end="", flush=True)
                sleep(1.0)
            print("press the trigger, perform the gesture, press the trigger again", flush=True)
            result = record(source, path, wait_for_trigger=True, on_event=_View(), overwrite=True)
            print(f"  take {k}: {result.duration:.2f} s, {result.samples} samples → {path}", flush=True)
            paths.append(str(path))
    finally:
        source.close()
    return paths


def cmd_learn(args) -> int:
    from doodle.app.cli.options import load_input, segmenter_params
    from doodle.core.files import atomic_write
    from grammar.learn import learn
    from grammar.library import compile_library, overlaps
    from grammar.shapes import save_paths
    from library.manifest import ActionDef, Interaction, Library, builtin, combine, format_library, load_library, \
        manifest_path

    if args.record:
        args.examples = record_takes(args.name, Path(args.library), TAKES)
    if len(args.examples) < 2:
        raise DoodleError(f"give at least two example files (three are best), got {len(args.examples)}")
    name = args.name.strip()
    if not name or any(c in name for c in "\"\n[]"):
        raise DoodleError(f"{args.name!r} is not a usable action name")
    params, mounts = segmenter_params(args)
    doodles = [load_input(path, args, mounts) for path in args.examples]
    tracks = doodles[0].names if args.tracks else doodles[0].names[:1]
    for path, d in zip(args.examples, doodles):
        missing = [t for t in tracks if t not in d.names]
        if missing:
            raise DoodleError(f"{path}: no track {missing[0]!r} (tracks: {', '.join(d.names)})")
    folder = Path(args.library)
    existing = load_library(folder) if manifest_path(folder).exists() else Library(folder.resolve().name, (),
                                                                                   str(manifest_path(folder)))
    names = [name] if len(tracks) == 1 else [f"{name}.{t}" for t in tracks]
    clash = [n for n in names + [name] if n in existing.names or n in {i.name for i in existing.interactions}]
    if clash and not args.replace:
        raise DoodleError(f"{manifest_path(folder)}: {clash[0]!r} exists already; choose another name or "
                          "--replace it")
    start = time.perf_counter()
    learned = []
    for track in tracks:
        examples = [(d.track(track).t, d.track(track).p, d.track(track).q) for d in doodles]
        try:
            learned.append(learn(examples, doodles[0].rate, params))
        except DoodleError as e:
            raise DoodleError(f"track {track}: {e}") from None
    took = time.perf_counter() - start
    source = ", ".join(Path(p).name for p in args.examples)
    shapes = [folder / "shapes" / f"{n}.npz" for n in names]
    new = [ActionDef(n, lrn.expression, False, True, False, note=f"learned from {source}",
                     source=str(manifest_path(folder)), tolerance=lrn.tolerance, shape=str(shape.resolve()),
                     track=track if len(tracks) > 1 else None)
           for n, lrn, shape, track in zip(names, learned, shapes, tracks)]
    kept = tuple(a for a in existing.actions if a.name not in names)
    interactions = tuple(i for i in existing.interactions if i.name != name)
    if len(names) > 1:
        interactions += (Interaction(name, tuple(names)),)
    library = Library(existing.name, kept + tuple(new), existing.source, existing.roles, interactions,
                      existing.states)
    (folder / "shapes").mkdir(parents=True, exist_ok=True)
    for shape, lrn in zip(shapes, learned):  # first: compiling the library reads them
        save_paths(shape, lrn.paths)
    compiled = compile_library(combine(None if args.no_builtin else builtin(), library))
    atomic_write(manifest_path(folder), [format_library(library, folder.resolve())])
    for n, lrn, track in zip(names, learned, tracks):
        print(f"{n} ({track}, learned in {took * 1000 / len(tracks):.0f} ms, tolerance {lrn.tolerance:g} edits): "
              f"{lrn.expression}")
        for k, s in enumerate(lrn.strings):
            label = "average" if k == len(args.examples) else Path(args.examples[k]).name
            print(f"    {label:<24} {' '.join(s)}")
    collisions = [o for n in names for o in overlaps(compiled, only=n)]
    if collisions:
        print("overlaps (a token string both accept — keep, rename or re-record):")
        for o in collisions:
            other = o.second if o.first in names else o.first
            print(f"  {o.first if o.first in names else o.second} ~ {other}: {' '.join(o.witness)}")
    else:
        print("no overlap with the other actions")
    print(f"{manifest_path(folder)}: {len(library.actions)} actions")
    return 0
