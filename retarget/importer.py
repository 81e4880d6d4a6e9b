"""Build a library from a folder of BVH clips (Mixamo, CMU, Bandai Namco, DeepMimic…).

Each file becomes a clip of an action, copied into the library's ``clips`` folder (a library
names files inside its own folder only, so it can be moved or sent, and one that is sent
cannot make the program read elsewhere: :func:`doodle.core.files.within`). The action is
named by the first rule of a mapping file that matches the file name, else from the file
name itself (Bandai's ``dataset-1_{content}_{style}_{id}`` gives ``content``; otherwise the
stem without a trailing take number). A name that is a built-in action, or a known alias of one (``walk-left`` →
Side Walk Left), takes that action's expression and flags, so the imported clips are
recognised at once; other actions are clip-only until the mapping file or the learning
wizard gives them an expression. An alias of a travelling action (Walk, Walk Back, Side Walk
Left, Side Walk Right) is taken only by a clip that travels the way that action means,
relative to where the clip faces (:func:`retarget.clips.fits`): Bandai's ``walk-left`` is
a forward walk towards the performer's left, facing that way, not a side step, so it stays
an action of its own (with a note saying so). Stages, cycle lengths and foot contacts are
extracted from the clips when the library is loaded (:mod:`retarget.clips`) and reported here.

Mapping file (TOML)::

    [[map]]
    match = "*punch*"          # a glob on the file name
    action = "Punch"           # the action the clip belongs to
    expression = "T_N_Z T_Z"   # optional
    cyclic = false             # optional flags
"""

from __future__ import annotations

import fnmatch
import re
import shutil
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.files import atomic_write, safe_file_name
from library.folder import check_library_folder, updating
from library.manifest import FLAGS, ActionDef, Library, builtin, format_library, load_library, manifest_path
from retarget.clips import FIT, travel_directions

ALIASES = {
    "walk": "Walk", "walk-back": "Walk Back", "walkback": "Walk Back", "walk-left": "Side Walk Left",
    "walk-right": "Side Walk Right", "kick": "Kick", "punch": "Punch", "jump": "Jump", "backflip": "Back Flip",
    "back-flip": "Back Flip", "dance": "Dance", "dance-short": "Dance", "idle": "Idle", "stomp": "Stomp",
    "throw": "Throw", "bye": "Greet", "byebye": "Greet", "greet": "Greet",
    "raise-up-both-hands": "Raise Arms", "raise-up-right-hand": "Raise One Arm", "raise-up-left-hand": "Raise One Arm",
}
CYCLIC_WORDS = ("walk", "run", "jog", "dash", "crawl")
BANDAI = re.compile(r"^dataset-\d+_(?P<content>.+?)_(?P<style>[a-z-]+)_(?P<take>\d+)$")


def read_map(path) -> list[dict]:
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as e:
        raise DoodleError(f"{path}: cannot read: {e.strerror or e}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise DoodleError(f"{path}: not valid TOML: {e}") from None
    rules = data.get("map", [])
    if not isinstance(rules, list):
        raise DoodleError(f"{path}: 'map' must be an array of tables ([[map]])")
    for i, rule in enumerate(rules, 1):
        if not isinstance(rule, dict) or not isinstance(rule.get("match"), str) or not isinstance(rule.get("action"), str):
            raise DoodleError(f"{path}: map #{i}: needs 'match' (a glob) and 'action' (a name)")
        extra = set(rule) - {"match", "action", "expression", *FLAGS}
        if extra:
            raise DoodleError(f"{path}: map #{i}: unknown field {sorted(extra)[0]!r}")
    return rules


def name_of(path: Path) -> str:
    stem = path.stem
    m = BANDAI.match(stem)
    if m:
        return m.group("content")
    return re.sub(r"[_-]?\d+$", "", stem) or stem


def _travel(path: Path) -> float | None:
    """Where a clip travels relative to its facing (radians), as :mod:`retarget.clips` reads it."""
    from retarget.analysis import travel_yaw
    from retarget.bvh import read_bvh
    from retarget.clips import face_front

    return travel_yaw(face_front(read_bvh(path)))


def plan_library(folder, name: str, mapping=None, include: str = "*.bvh", source: str = "") -> Library:
    """The library the BVH files of ``folder`` make, its clips still where they are (nothing
    written): loaded and checked from there, errors name the files as the user knows them.
    ``source`` is the manifest it will be written to, for messages."""
    folder = Path(folder)
    if not folder.is_dir():
        raise DoodleError(f"{folder}: not a folder of BVH files")
    files = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".bvh" and fnmatch.fnmatch(p.name, include)
                   and p.is_file())
    if not files:
        raise DoodleError(f"{folder}: no BVH files matching {include!r}")
    rules = read_map(mapping) if mapping else []
    known = {a.name: a for a in builtin().actions}
    directions = travel_directions(builtin())
    actions: dict[str, ActionDef] = {}
    notes: dict[str, str] = {}
    for path in files:
        rule = next((r for r in rules if fnmatch.fnmatch(path.name, r["match"])), None)
        raw = rule["action"] if rule else name_of(path)
        action_name = ALIASES.get(raw.lower(), raw)
        if not rule and action_name in directions and action_name != raw:
            travel = _travel(path)
            if travel is None or abs(float(np.angle(np.exp(1j * (travel - directions[action_name]))))) > FIT:
                way = "on the spot" if travel is None else f"{np.degrees(travel):+.0f}° from where it faces"
                notes.setdefault(raw, f"{path.name} travels {way}, not the way {action_name} does "
                                      f"({np.degrees(directions[action_name]):+.0f}°): kept as an action of its own")
                action_name = raw
        if action_name in actions:
            actions[action_name] = replace(actions[action_name], clips=actions[action_name].clips + (str(path.resolve()),))
            continue
        base = known.get(action_name)
        flags = {f: getattr(base, f) for f in FLAGS} if base else {
            "cyclic": any(w in raw.lower() for w in CYCLIC_WORDS), "in_place": not any(
                w in raw.lower() for w in CYCLIC_WORDS), "jumping": "jump" in raw.lower() or "flip" in raw.lower()}
        expression = base.expression if base else ""
        if rule:
            expression = rule.get("expression", expression)
            flags.update({f: rule[f] for f in FLAGS if f in rule})
        actions[action_name] = ActionDef(action_name, expression, source=str(source),
                                         clips=(str(path.resolve()),), note=notes.get(action_name, ""), **flags)
    return Library(name, tuple(actions.values()), str(source))


IMPORTED = ("library.toml", "clips")  # what an import writes anew in a library folder (the rest is kept)


def write_library(library: Library, output) -> Library:
    """Copy ``library``'s clips into ``output/clips`` and write its manifest there: a library
    is self-contained (it names files inside its folder only, so it can be moved or sent);
    returns it as written. ``output`` is a fresh folder (a staging one: :func:`import_library`)."""
    output = Path(output)
    (output / "clips").mkdir(parents=True, exist_ok=True)
    taken: set[str] = set()
    copied = {}
    for action in library.actions:
        for clip in action.clips:
            name = safe_file_name(Path(clip).stem, taken) + ".bvh"
            taken.add(name[:-4])
            try:
                shutil.copyfile(clip, output / "clips" / name)
            except OSError as e:
                raise DoodleError(f"{clip}: cannot copy into {output / 'clips'}: {e.strerror or e}") from None
            copied[clip] = str((output / "clips" / name).resolve())
    written = replace(library, actions=tuple(replace(a, clips=tuple(copied[c] for c in a.clips))
                                             for a in library.actions))
    atomic_write(manifest_path(output), [format_library(written, output.resolve())])
    return written


def import_library(folder, name: str, output, mapping=None, include: str = "*.bvh") -> Library:
    """Write a library for the BVH files of ``folder`` into ``output`` (replacing the
    manifest and clips of a library there only once the new ones are complete); returns it."""
    output = Path(output)
    check_library_folder(output)
    library = plan_library(folder, name, mapping, include, str(manifest_path(output)))
    with updating(output, IMPORTED) as stage:
        write_library(library, stage)
    return load_library(output)
