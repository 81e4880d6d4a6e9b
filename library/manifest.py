"""Library manifests: actions declared in TOML, validated on load.

A library is a folder holding ``library.toml``::

    [library]
    name = "mine"
    format = 1
    states = ["standing"]            # optional: state variables true for every character at the start

    [[actions]]
    name = "Wave"
    expression = "(T_X | T_N_X)+"   # over the Segmenter's compacted tokens
    cyclic = false                   # repeats along the path (walks)
    in_place = true                  # does not travel
    jumping = false                  # leaves the ground
    note = "free text"               # optional
    clips = ["clips/wave.bvh"]       # optional: BVH files, relative to the library folder and in it
    stages = [4, 9, 20, 26]          # optional: frames ending preparation, anticipation,
                                     #   execution and follow-through (else extracted)
    cycle_length = 1.3               # optional, cyclic clips: metres travelled per cycle
    tolerance = 6                    # optional: token edits a performance may differ by (default: the Matcher's 2)
    shape = "shapes/wave.npz"        # optional: the examples' paths (learned actions; grammar.shapes)
    track = "c0"                     # optional: the only track it is recognised on
    tracks = ["c0", "c1"]            # optional: tracks performing it together (a two-handed action,
                                     #   one gesture: recognised on the first, its shape read on all)
    requires = ["standing"]          # optional behaviour (§6.3.3): state variables that must be true,
    forbids = ["fallen"]             #   … that must be false before it,
    sets = ["fallen"]                #   … made true and
    clears = ["standing"]            #   … made false when it ends

    [skeleton]                       # optional: joints playing each role in the clips
    pelvis = "Hips"
    chest = "Spine2"
    head = "Head"
    left_foot = "LeftFoot"
    right_foot = "RightFoot"
    left_hand = "LeftHand"
    right_hand = "RightHand"

    [[interactions]]                 # optional: actions performed together (§6.2)
    name = "Slap"
    actions = ["Slap", "Slapped"]    # one per character, each an action of the library
    constraints = ["D(0, 1, Personal)", "V(0, 1, 0.5)"]  # optional (§6.3; their syntax is
                                                         #   checked where compiled: grammar.library)

Errors name the file, the action and the field. Paths (``clips``, ``shape``, ``pair``)
must lead to files inside the library's folder (:func:`doodle.core.files.within`): no
absolute paths, no ``..`` out of it, no NUL — a library someone sends cannot make the
program read elsewhere. A user library extends the built-in one
and overrides its actions of the same name (:func:`combine`); an overriding action without
an expression keeps the one it overrides. The expression's syntax is checked where it is
compiled (:mod:`grammar.library`), and joint names where clips are loaded
(:mod:`retarget.clips`), with the action and the column or field named.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

from doodle.core.errors import DoodleError
from doodle.core.files import within

BUILTIN = Path(__file__).resolve().parent / "builtin"
RESERVED = {"unknown"}
FLAGS = ("cyclic", "in_place", "jumping")
BEHAVIOUR = ("requires", "forbids", "sets", "clears")  # §6.3.3 pre- and post-conditions
ACTION_KEYS = {"name", "expression", "note", "flags_note", "clips", "stages", "cycle_length", "tolerance",
               "interaction_only", "shape", "track", "tracks", *BEHAVIOUR, *FLAGS}
ROLES = ("pelvis", "chest", "head", "left_foot", "right_foot", "left_hand", "right_hand")


@dataclass(frozen=True)
class ActionDef:
    """One action of a library manifest: its expression, flags, clips and behaviour."""

    name: str
    expression: str
    cyclic: bool
    in_place: bool
    jumping: bool
    note: str = ""
    source: str = ""  # the manifest it came from
    clips: tuple[str, ...] = ()  # absolute paths of BVH clips
    stages: tuple[int, ...] | None = None  # frames ending the first four stages
    cycle_length: float | None = None  # metres per cycle
    roles: dict = field(default_factory=dict)  # its library's [skeleton] table: role -> joint name
    tolerance: float | None = None  # edits a performance may be from the expression (None: the Matcher's)
    interaction_only: bool = False  # its expression is a role of an interaction, never matched alone
    shape: str | None = None  # absolute path of the .npz of its examples' paths (grammar.shapes)
    track: str | None = None  # recognised on this track only (None: on any)
    tracks: tuple[str, ...] = ()  # a two-handed action: the tracks performing it together, ``track`` first
    requires: tuple[str, ...] = ()  # behaviour (§6.3.3): state variables true before,
    forbids: tuple[str, ...] = ()  # false before,
    sets: tuple[str, ...] = ()  # made true and
    clears: tuple[str, ...] = ()  # made false when it ends


@dataclass(frozen=True)
class Interaction:
    """An interaction of a library manifest: its actions, constraints, contact and placement."""

    name: str
    actions: tuple[str, ...]
    constraints: tuple[str, ...] = ()  # in the thesis's notation, e.g. "D(0, 1, Personal)" (§6.3)
    contact: tuple[str, ...] = ()  # (role 0's joint role, role 1's joint role) that meet, e.g. right_hand, head
    placement: tuple[float, float, float] | None = None  # role 1's (x right, z front, turn°) from role 0 (§6.2.2)
    pair: tuple[str, ...] = ()  # absolute paths of a two-character clip: one BVH per role, one timeline


@dataclass(frozen=True)
class Library:
    """An action library as its manifest (library.toml) defines it."""

    name: str
    actions: tuple[ActionDef, ...]
    source: str
    roles: dict = field(default_factory=dict)  # role -> joint name
    interactions: tuple[Interaction, ...] = ()
    states: tuple[str, ...] = ()  # state variables true for every character at the start (§6.3.3)

    @property
    def names(self) -> list[str]:
        return [a.name for a in self.actions]

    def action(self, name: str) -> ActionDef:
        for a in self.actions:
            if a.name == name:
                return a
        raise DoodleError(f"{self.source}: no action {name!r}")


def manifest_path(location) -> Path:
    path = Path(location)
    return path / "library.toml" if path.is_dir() or path.suffix != ".toml" else path


def load_library(location) -> Library:
    """Read and validate a library folder (or its ``library.toml``)."""
    path = manifest_path(location)
    if not path.exists():
        raise DoodleError(f"{path}: no library manifest here (expected {path.name})")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise DoodleError(f"{path}: not valid TOML: {e}") from None
    except OSError as e:
        raise DoodleError(f"{path}: cannot read: {e.strerror}") from None
    head = data.get("library")
    if not isinstance(head, dict) or not isinstance(head.get("name"), str) or not head["name"].strip():
        raise DoodleError(f"{path}: [library] needs a name")
    if head.get("format", 1) != 1:
        raise DoodleError(f"{path}: library format {head.get('format')!r} is not supported (this version reads 1)")
    unknown = set(data) - {"library", "actions", "skeleton", "interactions"}
    if unknown:
        raise DoodleError(f"{path}: unknown section {sorted(unknown)[0]!r}")
    entries = data.get("actions", [])
    if not isinstance(entries, list):
        raise DoodleError(f"{path}: 'actions' must be an array of tables ([[actions]])")
    actions, seen = [], set()
    for i, entry in enumerate(entries, 1):
        actions.append(_action(entry, i, path))
        name = actions[-1].name
        if name in seen:
            raise DoodleError(f"{path}: action {name!r} is defined twice")
        seen.add(name)
    roles = data.get("skeleton", {})
    if not isinstance(roles, dict):
        raise DoodleError(f"{path}: [skeleton] must be a table of role = joint name")
    for role, joint in roles.items():
        if role not in ROLES:
            raise DoodleError(f"{path}: skeleton.{role}: unknown role (known: {', '.join(ROLES)})")
        if not isinstance(joint, str) or not joint:
            raise DoodleError(f"{path}: skeleton.{role}: expected a joint name, got {joint!r}")
    interactions = tuple(_interaction(e, i, path, seen) for i, e in enumerate(data.get("interactions", []), 1))
    actions = [replace(a, roles=dict(roles)) for a in actions]
    states = _names(head.get("states", []), f"{path}: [library] states")
    return Library(head["name"], tuple(actions), str(path), dict(roles), interactions, states)


def _names(value, where: str) -> tuple[str, ...]:
    """A list of state-variable names (§6.3.3)."""
    if not isinstance(value, list) or not all(isinstance(v, str) and v.strip() and v == v.strip() and " " not in v
                                              for v in value):
        raise DoodleError(f"{where}: must be a list of state names such as [\"standing\"] (no spaces)")
    return tuple(value)


def _interaction(entry, i: int, path: Path, names: set) -> Interaction:
    if not isinstance(entry, dict) or not isinstance(entry.get("name"), str):
        raise DoodleError(f"{path}: interaction #{i}: needs a name")
    where = f"{path}: interaction {entry['name']!r}"
    acts = entry.get("actions")
    if not isinstance(acts, list) or len(acts) < 2 or not all(isinstance(a, str) for a in acts):
        raise DoodleError(f"{where}: field 'actions' must list at least two action names")
    extra = set(entry) - {"name", "actions", "note", "constraints", "contact", "placement", "pair"}
    if extra:
        raise DoodleError(f"{where}: unknown field {sorted(extra)[0]!r}")
    constraints = entry.get("constraints", [])
    if not isinstance(constraints, list) or not all(isinstance(c, str) for c in constraints):
        raise DoodleError(f"{where}: field 'constraints' must be a list of strings such as \"D(0, 1, Personal)\"")
    contact = entry.get("contact", [])
    if not isinstance(contact, list) or (contact and (len(contact) != 2 or not all(c in ROLES for c in contact))):
        raise DoodleError(f"{where}: field 'contact' must be two joint roles (role 0's, role 1's) among "
                          f"{', '.join(ROLES)}, e.g. [\"right_hand\", \"head\"]")
    placement = entry.get("placement")
    if placement is not None and (
            not isinstance(placement, list) or len(placement) != 3
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in placement)):
        raise DoodleError(f"{where}: field 'placement' must be [x, z, turn]: role 1's place to role 0's right and "
                          "front (metres) and its heading from role 0's (degrees), e.g. [0, 0.6, 180]")
    if placement is not None and len(acts) != 2:
        raise DoodleError(f"{where}: field 'placement' is for two-character interactions")
    pair = entry.get("pair", [])
    if not isinstance(pair, list) or (pair and (len(pair) != 2 or not all(isinstance(c, str) and c for c in pair))):
        raise DoodleError(f"{where}: field 'pair' must be two BVH files, role 0's and role 1's, of one "
                          "two-character clip")
    return Interaction(entry["name"], tuple(acts), tuple(constraints), tuple(contact),
                       tuple(float(v) for v in placement) if placement is not None else None,
                       tuple(str(within(path.parent, c, f"{where}: field 'pair'")) for c in pair))


def _action(entry, i: int, path: Path) -> ActionDef:
    where = f"{path}: action #{i}"
    if not isinstance(entry, dict):
        raise DoodleError(f"{where}: not a table")
    name = entry.get("name")
    if not isinstance(name, str) or not name.strip():
        raise DoodleError(f"{where}: field 'name' must be a non-empty string")
    where = f"{path}: action {name!r}"
    if name in RESERVED:
        raise DoodleError(f"{where}: the name {name!r} is reserved")
    extra = set(entry) - ACTION_KEYS
    if extra:
        raise DoodleError(f"{where}: unknown field {sorted(extra)[0]!r}")
    expression = entry.get("expression", "")
    if not isinstance(expression, str):
        raise DoodleError(f"{where}: field 'expression' must be a string")
    clips = entry.get("clips", [])
    if not isinstance(clips, list) or not all(isinstance(c, str) and c for c in clips):
        raise DoodleError(f"{where}: field 'clips' must be a list of BVH file paths")
    resolved = tuple(str(within(path.parent, c, f"{where}: field 'clips'")) for c in clips)
    stages = entry.get("stages")
    if stages is not None and (not isinstance(stages, list) or len(stages) != 4
                               or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in stages)
                               or stages != sorted(stages)):
        raise DoodleError(f"{where}: field 'stages' must be four increasing frame numbers "
                          f"(ends of preparation, anticipation, execution, follow-through)")
    cycle = entry.get("cycle_length")
    if cycle is not None and (not isinstance(cycle, (int, float)) or isinstance(cycle, bool) or not cycle > 0):
        raise DoodleError(f"{where}: field 'cycle_length' must be a positive number of metres")
    tolerance = entry.get("tolerance")
    if tolerance is not None and (not isinstance(tolerance, (int, float)) or isinstance(tolerance, bool)
                                  or not 0 <= tolerance <= 20):
        raise DoodleError(f"{where}: field 'tolerance' must be a number of edits from 0 to 20")
    interaction_only = entry.get("interaction_only", False)
    if not isinstance(interaction_only, bool):
        raise DoodleError(f"{where}: field 'interaction_only' must be true or false, not {interaction_only!r}")
    shape = entry.get("shape")
    if shape is not None and (not isinstance(shape, str) or not shape.endswith(".npz")):
        raise DoodleError(f"{where}: field 'shape' must be the path of a .npz file of example paths")
    track = entry.get("track")
    if track is not None and (not isinstance(track, str) or not track.strip()):
        raise DoodleError(f"{where}: field 'track' must be a track name such as \"c0\"")
    together = entry.get("tracks", [])
    if not isinstance(together, list) or (together and (
            len(together) < 2 or not all(isinstance(t, str) and t.strip() for t in together)
            or len(set(together)) != len(together) or (track is not None and track != together[0]))):
        raise DoodleError(f"{where}: field 'tracks' must list two or more distinct track names, the first being "
                          "'track' when that is given, e.g. [\"c0\", \"c1\"]")
    if together:
        track = together[0]
    behaviour = {key: _names(entry.get(key, []), f"{where}: field {key!r}") for key in BEHAVIOUR}
    for a, b in (("requires", "forbids"), ("sets", "clears")):
        both = set(behaviour[a]) & set(behaviour[b])
        if both:
            raise DoodleError(f"{where}: state {sorted(both)[0]!r} is in both {a!r} and {b!r}")
    flags = {}
    for flag in FLAGS:
        value = entry.get(flag, False)
        if not isinstance(value, bool):
            raise DoodleError(f"{where}: field {flag!r} must be true or false, not {value!r}")
        flags[flag] = value
    return ActionDef(name, expression, note=str(entry.get("note", "")), source=str(path), clips=resolved,
                     stages=tuple(stages) if stages is not None else None,
                     cycle_length=float(cycle) if cycle is not None else None,
                     tolerance=float(tolerance) if tolerance is not None else None,
                     interaction_only=interaction_only,
                     shape=str(within(path.parent, shape, f"{where}: field 'shape'")) if shape is not None else None,
                     track=track, tracks=tuple(together),
                     **behaviour, **flags)


def builtin() -> Library:
    """The built-in library shipped with the package."""
    return load_library(BUILTIN)


def load_combined(library_dir=None, use_builtin: bool = True) -> tuple[Library, Library | None]:
    """The built-in library (unless ``use_builtin`` is False) extended or overridden by the
    one in ``library_dir``; and that user library alone (None without one)."""
    user = load_library(library_dir) if library_dir else None
    if not use_builtin and user is None:
        raise DoodleError("no actions: the built-in library is left out and no user library is given")
    return combine(builtin() if use_builtin else None, user), user


def combine(base: Library | None, user: Library | None) -> Library:
    """``user``'s actions override ``base``'s of the same name; new ones come after."""
    if base is None or user is None:
        lib = base or user
        if lib is None:
            raise DoodleError("no library: neither the built-in one nor a user library")
        return lib
    mine = {a.name: a for a in user.actions}
    merged = []
    for a in base.actions:
        over = mine.pop(a.name, None)
        merged.append(a if over is None else (over if over.expression else replace(over, expression=a.expression)))
    merged += [a for a in user.actions if a.name in mine]
    roles = {**base.roles, **user.roles}
    names = {i.name for i in user.interactions}
    interactions = tuple(i for i in base.interactions if i.name not in names) + user.interactions
    return Library(f"{base.name}+{user.name}", tuple(merged), user.source, roles, interactions,
                   tuple(dict.fromkeys(base.states + user.states)))


def _toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and every control character escaped (a raw
    one, a NUL say, would make the file unreadable)."""
    def escaped(c: str) -> str:
        if c in '"\\':
            return "\\" + c
        if ord(c) < 0x20 or ord(c) == 0x7F:
            return {"\n": "\\n", "\t": "\\t"}.get(c, f"\\u{ord(c):04x}")
        return c

    return '"' + "".join(escaped(c) for c in text) + '"'


def format_library(library: Library, folder) -> str:
    """TOML text of a library whose clip paths are written relative to ``folder``."""
    import os

    lines = ["[library]", f"name = {_toml_string(library.name)}", "format = 1"]
    if library.states:
        lines.append(f"states = [{', '.join(_toml_string(v) for v in library.states)}]")
    lines.append("")
    if library.roles:
        lines.append("[skeleton]")
        lines += [f"{role} = {_toml_string(joint)}" for role, joint in library.roles.items()]
        lines.append("")
    for a in library.actions:
        lines += ["[[actions]]", f"name = {_toml_string(a.name)}"]
        if a.expression:
            lines.append(f"expression = {_toml_string(a.expression)}")
        lines += [f"{flag} = {str(getattr(a, flag)).lower()}" for flag in FLAGS]
        if a.clips:
            rel = [os.path.relpath(c, folder) for c in a.clips]
            lines.append("clips = [" + ", ".join(_toml_string(c) for c in rel) + "]")
        if a.stages is not None:
            lines.append(f"stages = [{', '.join(str(s) for s in a.stages)}]")
        if a.cycle_length is not None:
            lines.append(f"cycle_length = {a.cycle_length:.4f}")
        if a.tolerance is not None:
            lines.append(f"tolerance = {a.tolerance:g}")
        if a.interaction_only:
            lines.append("interaction_only = true")
        if a.shape is not None:
            lines.append(f"shape = {_toml_string(os.path.relpath(a.shape, folder))}")
        if a.track is not None:
            lines.append(f"track = {_toml_string(a.track)}")
        if a.tracks:
            lines.append(f"tracks = [{', '.join(_toml_string(t) for t in a.tracks)}]")
        for key in BEHAVIOUR:
            if getattr(a, key):
                lines.append(f"{key} = [{', '.join(_toml_string(v) for v in getattr(a, key))}]")
        if a.note:
            lines.append(f"note = {_toml_string(a.note)}")
        lines.append("")
    for i in library.interactions:
        lines += ["[[interactions]]", f"name = {_toml_string(i.name)}",
                  "actions = [" + ", ".join(_toml_string(x) for x in i.actions) + "]"]
        if i.constraints:
            lines.append("constraints = [" + ", ".join(_toml_string(c) for c in i.constraints) + "]")
        if i.contact:
            lines.append("contact = [" + ", ".join(_toml_string(c) for c in i.contact) + "]")
        if i.placement is not None:
            lines.append("placement = [" + ", ".join(f"{v:g}" for v in i.placement) + "]")
        if i.pair:
            lines.append("pair = [" + ", ".join(_toml_string(os.path.relpath(c, folder)) for c in i.pair) + "]")
        lines.append("")
    return "\n".join(lines)
