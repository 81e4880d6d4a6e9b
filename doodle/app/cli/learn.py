"""``doodle learn``: teach the program a new action from a few performed examples (§4.2.5).

The action is added to a user library folder (created if missing) with the learned
expression and its examples' shapes (paths and controller orientations); with two tracks
(``--tracks c0,c1``) it is one two-handed action ``NAME`` (``tracks = ["c0", "c1"]``): its
expression is the first track's, its shapes both hands' resampled together, so it is
recognised as one gesture — one decision over both tracks. The overlap check against the library then says which
actions would collide and on which token string, so the person can keep, rename or re-record.

The library changes whole or not at all (:mod:`library.folder`): its new version — shapes,
manifest — is written beside it and swapped in once it is complete and compiles, so a failed
or killed run leaves it as it was. An action's name is not a path: its shape file gets a safe
name of its own (``shapes/NAME.npz`` for ordinary names).
"""

from __future__ import annotations

import itertools
import time
from pathlib import Path

from doodle.core.errors import DoodleError


def add_arguments(p) -> None:
    """The arguments of ``doodle learn``."""
    from doodle.app.cli.options import input_options, segmenter_options

    p.add_argument("name", help="the new action's name")
    p.add_argument("examples", nargs="*", help="doodle or CSV files, one performance each")
    p.add_argument("--library", required=True, metavar="DIR", help="user library to add it to (created if missing; "
                   "changed only when learning succeeds)")
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


def record_takes(name: str, folder: Path, takes: int = TAKES, sleep=time.sleep, *, compiled=None,
                 params=None, mounts: dict | None = None) -> list[str]:
    """The wizard: ``takes`` performances recorded with the controllers, each started and
    stopped with the trigger after a countdown, shown live — tokens, and the actions the
    library ``compiled`` recognises in them as ``doodle recognize`` would (its learned
    shapes included; None: the tokens alone); saved in ``folder/takes/`` under names no
    earlier take has (a take is a performance: never overwritten)."""
    from doodle.app.cli.record import _View
    from doodle.app.recorder import record
    from doodle.core.files import output_dir, safe_file_name
    from doodle.input.segmenter import SegmenterParams

    try:
        source = open_source()
    except DoodleError as e:
        raise DoodleError(f"{e}; or record each example elsewhere and give the files: doodle learn NAME EX1 EX2 EX3 "
                          "--library DIR") from None
    paths = []
    try:
        where = output_dir(folder / "takes")
        stem = safe_file_name(name)
        free = (p for p in (where / f"{stem}_{k}.doodle" for k in itertools.count(1)) if not p.exists())
        for k in range(1, takes + 1):
            path = next(free)
            print(f"take {k}/{takes} of {name!r}: ", end="", flush=True)
            for n in range(COUNTDOWN, 0, -1):
                print(f"{n}… ", end="", flush=True)
                sleep(1.0)
            print("press the trigger, perform the gesture, press the trigger again", flush=True)
            result = record(source, path, wait_for_trigger=True, on_event=_View(), compiled=compiled,
                            recognise=compiled is not None, params=params or SegmenterParams(), mounts=mounts)
            print(f"  take {k}: {result.duration:.2f} s, {result.samples} samples → {path}", flush=True)
            paths.append(str(path))
    finally:
        source.close()
    return paths


NAME_LIMIT = 100  # characters in an action name


def check_name(text: str) -> str:
    """The action name as given (spaces around it dropped), refused where it could not be
    written into a manifest or shown on one line. It is not a path: its shape file is named
    by :func:`doodle.core.files.safe_file_name`."""
    import unicodedata

    name = text.strip()
    shown = repr(name if len(name) <= 40 else name[:37] + "...")
    if not name or any(c in name for c in "\"[]"):
        raise DoodleError(f"action name {shown}: not usable (empty, or holds a quote or brackets)")
    if any(unicodedata.category(c) == "Cc" for c in name):
        raise DoodleError(f"action name {shown}: holds control characters (such as NUL or a line break)")
    if len(name) > NAME_LIMIT:
        raise DoodleError(f"action name {shown}: too long ({len(name)} characters; at most {NAME_LIMIT})")
    return name


def learn_action(existing, name: str, doodles: list, tracks: list[str], params, folder: Path, source: str = ""):
    """What ``doodle learn`` adds to the library ``existing`` (in ``folder``): the action
    ``name`` learned from ``doodles`` (one performance each) on ``tracks`` — one track, or
    several performing one two-handed gesture (recognised on the first, its shape read on
    all). Returns the new library, its shape files to write (``{file name: (paths,
    quats, seconds)}``: :func:`grammar.shapes.save_paths`), what was learned per track and
    the seconds learning took."""
    import numpy as np

    from doodle.core.files import safe_file_name
    from grammar.learn import learn
    from grammar.shapes import sample, times
    from library.manifest import ActionDef, Library, manifest_path

    start = time.perf_counter()
    learned = []
    for track in tracks:
        examples = [(d.track(track).t, d.track(track).p, d.track(track).q) for d in doodles]
        try:
            learned.append(learn(examples, doodles[0].rate, params))
        except DoodleError as e:
            raise DoodleError(f"track {track}: {e}") from None
    shapes, elapsed = [], []
    for d, (a, b) in zip(doodles, learned[0].spans):  # the tracks' samples where every one of them is tracked,
        keep = np.logical_and.reduce([d.track(t).valid for t in tracks])  # resampled together
        poses = [(d.track(t).p[keep], d.track(t).q[keep]) for t in tracks]
        shapes.append(sample(poses))
        clock = d.track(tracks[0]).t
        elapsed.append(times(poses, clock[keep], (clock[a], clock[b - 1])))  # over the first track's motion
    took = time.perf_counter() - start
    learned[0] = _not_empty(learned[0])
    replaced = {name} | {f"{name}.{t}" for t in tracks}  # and the halves of a pair learned before
    kept = tuple(a for a in existing.actions if a.name not in replaced)
    taken = {Path(a.shape).stem for a in kept if a.shape}
    file = safe_file_name(name, taken) + ".npz"
    home = Path(folder).resolve()
    lead = learned[0]
    action = ActionDef(name, lead.expression, False, True, False, note=f"learned from {source}" if source else "",
                       source=str(manifest_path(folder)), tolerance=lead.tolerance, shape=str(home / "shapes" / file),
                       track=tracks[0] if len(tracks) > 1 else None, tracks=tuple(tracks) if len(tracks) > 1 else ())
    interactions = tuple(i for i in existing.interactions if i.name != name)
    library = Library(existing.name, kept + (action,), existing.source, existing.roles, interactions, existing.states)
    paths = np.array([p for p, _ in shapes])
    quats = np.array([q for _, q in shapes])
    return library, {file: (paths, quats, np.array(lead.seconds), np.array(elapsed))}, learned, took


def _not_empty(learned):
    """Examples so different (several people's, say) that no token is in all of them give an
    expression of optional parts only, which would also match no motion at all: it then
    needs one of the tokens the examples end with after it (what every example does)."""
    from dataclasses import replace

    from grammar.automata import compile_expression
    from grammar.expr import parse

    if not compile_expression(parse(learned.expression)).accept[0]:
        return learned
    last = sorted({s[-1] for s in learned.strings if s})
    end = last[0] if len(last) == 1 else "(" + " | ".join(last) + ")"
    return replace(learned, expression=f"{learned.expression} {end}")


def cmd_learn(args) -> int:
    from doodle.app.cli.options import load_input, segmenter_params
    from doodle.core.files import atomic_write
    from grammar.library import compile_library, overlaps
    from grammar.shapes import save_paths
    from library.folder import check_library_folder, updating
    from library.manifest import Library, builtin, combine, format_library, load_library, manifest_path

    name = check_name(args.name)
    folder = check_library_folder(Path(args.library))
    existing = load_library(folder) if manifest_path(folder).exists() else Library(folder.resolve().name, (),
                                                                                   str(manifest_path(folder)))

    def clashing(names):
        clash = [n for n in names if n in existing.names or n in {i.name for i in existing.interactions}]
        if clash and not args.replace:
            raise DoodleError(f"{manifest_path(folder)}: {clash[0]!r} exists already; choose another name or "
                              "--replace it")

    clashing([name])  # before any recording
    params, mounts = segmenter_params(args)
    if args.record:
        live = combine(None if args.no_builtin else builtin(), existing)  # shown live: what recognize would say
        recognisable = any(a.expression.strip() and not a.interaction_only for a in live.actions)
        args.examples = record_takes(name, folder, TAKES, compiled=compile_library(live) if recognisable else None,
                                     params=params, mounts=mounts)
    if len(args.examples) < 2:
        raise DoodleError(f"give at least two example files (three are best), got {len(args.examples)}")
    doodles = [load_input(path, args, mounts) for path in args.examples]
    tracks = doodles[0].names if args.tracks else doodles[0].names[:1]
    for path, d in zip(args.examples, doodles):
        missing = [t for t in tracks if t not in d.names]
        if missing:
            raise DoodleError(f"{path}: no track {missing[0]!r} (tracks: {', '.join(d.names)})")
    clashing([name] + ([f"{name}.{t}" for t in tracks] if len(tracks) > 1 else []))
    library, new, learned, took = learn_action(existing, name, doodles, tracks, params, folder,
                                               ", ".join(Path(p).name for p in args.examples))
    with updating(folder) as stage:  # the library changes whole once all is written, or not at all
        (stage / "shapes").mkdir(exist_ok=True)
        for file, shape in new.items():
            save_paths(stage / "shapes" / file, *shape)
        atomic_write(manifest_path(stage), [format_library(library, folder.resolve())])
        compiled = compile_library(combine(None if args.no_builtin else builtin(), load_library(stage)))
    names = [name]
    together = "+".join(tracks)
    for track, lrn in zip(tracks, learned):
        if track == tracks[0]:
            print(f"{name} ({together}, learned in {took * 1000:.0f} ms, tolerance {lrn.tolerance:g} edits): "
                  f"{lrn.expression}")
        else:  # the other hand's tokens: shown, its shape read with the first's
            print(f"  {track} alone would be: {lrn.expression}")
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
