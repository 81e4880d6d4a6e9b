"""Library manifests: actions declared in TOML, validated on load.

A library is a folder holding ``library.toml``::

    [library]
    name = "mine"
    format = 1

    [[actions]]
    name = "Wave"
    expression = "(T_X | T_N_X)+"   # over the Segmenter's compacted tokens
    cyclic = false                   # repeats along the path (walks)
    in_place = true                  # does not travel
    jumping = false                  # leaves the ground
    note = "free text"               # optional

Errors name the file, the action and the field. A user library extends the built-in one
and overrides its actions of the same name (:func:`combine`). The expression's syntax is
checked where it is compiled (:mod:`grammar.library`), with the action and column named.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from doodle.errors import DoodleError

BUILTIN = Path(__file__).resolve().parent / "builtin"
RESERVED = {"unknown"}
FLAGS = ("cyclic", "in_place", "jumping")
ACTION_KEYS = {"name", "expression", "note", "flags_note", *FLAGS}


@dataclass(frozen=True)
class ActionDef:
    name: str
    expression: str
    cyclic: bool
    in_place: bool
    jumping: bool
    note: str = ""
    source: str = ""  # the manifest it came from


@dataclass(frozen=True)
class Library:
    name: str
    actions: tuple[ActionDef, ...]
    source: str

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
    unknown = set(data) - {"library", "actions"}
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
    return Library(head["name"], tuple(actions), str(path))


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
    expression = entry.get("expression")
    if not isinstance(expression, str) or not expression.strip():
        raise DoodleError(f"{where}: field 'expression' must be a non-empty string")
    flags = {}
    for flag in FLAGS:
        value = entry.get(flag, False)
        if not isinstance(value, bool):
            raise DoodleError(f"{where}: field {flag!r} must be true or false, not {value!r}")
        flags[flag] = value
    return ActionDef(name, expression, note=str(entry.get("note", "")), source=str(path), **flags)


def builtin() -> Library:
    """The built-in library shipped with the package."""
    return load_library(BUILTIN)


def combine(base: Library | None, user: Library | None) -> Library:
    """``user``'s actions override ``base``'s of the same name; new ones come after."""
    if base is None or user is None:
        lib = base or user
        if lib is None:
            raise DoodleError("no library: give --library DIR or drop --no-builtin")
        return lib
    mine = {a.name: a for a in user.actions}
    merged = [mine.pop(a.name, a) for a in base.actions] + [a for a in user.actions if a.name in mine]
    return Library(f"{base.name}+{user.name}", tuple(merged), user.source)
