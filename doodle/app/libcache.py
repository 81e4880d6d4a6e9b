"""The library work a compile repeats on every run, kept on disk between runs
(:mod:`doodle.core.cache`): each action's compiled automaton (DFA), the Matcher's tables,
and the library's clips read, put on the floor, turned to face front and analysed (roles,
stages, cycle length, foot contacts, travel direction).

Three kinds of entry, each named by a hash of what it is derived from, the code that derives
it (:func:`code_version`: the source of ``doodle.core``, ``grammar``, ``retarget``,
``library``, the pipeline and this module; numpy's version, and scipy's for the clips) and
:data:`FORMAT`:

* ``dfas`` — the minimal DFA of each expression, keyed by the expressions;
* ``automaton`` — the Matcher's tables (:class:`grammar.matcher.Automaton`) for one
  threshold and set of tracks, keyed by the recognisable actions' definitions;
* ``clips`` — every clip of the library as :func:`doodle.app.pipeline.load_for_compile`
  makes it (a user library's own and the built-in ones retarget onto its skeleton), and the
  travelling actions' directions, keyed by the combined library's definitions, the user's
  and the built-in one's, and the **contents** of every file they name (clips, shapes,
  two-character clips).

So an edited clip, manifest or module is a different key and the entry is rebuilt; an
entry that cannot be read back exactly as it was written (truncated, corrupt, another
format) is ignored and rebuilt. Results are the same with the cache cold or warm — every
array is stored as float64/int64/bool and read back bit for bit, every number in the JSON
header written with ``repr`` (exact) — which ``tests/test_startup.py`` checks on the
compiled output.
"""

from __future__ import annotations

import importlib
import json
import sys
import warnings
from dataclasses import asdict, dataclass, replace
from itertools import accumulate
from math import prod
from pathlib import Path

import numpy as np

from doodle.core import cache

FORMAT = 2  # 2: every field of the clips and DFAs one array (a few large members read faster than many)
_ROOT = Path(__file__).resolve().parents[2]
_CODE = ("doodle/core", "grammar", "retarget", "library", "doodle/app/libcache.py", "doodle/app/pipeline.py")
_VERSION: list[str] = []


def code_version() -> str | None:
    """A hash of the code whose results are cached (its source files' contents), numpy's
    version and :data:`FORMAT` (the clips' key adds scipy's); None when the sources cannot
    be read (an unusual installation: then nothing is cached)."""
    if not _VERSION:
        try:
            files = []
            for part in _CODE:
                path = _ROOT / part
                files += sorted(path.rglob("*.py")) if path.is_dir() else [path]
            parts = [FORMAT, sys.version_info[:2], np.__version__]
            for f in files:
                parts += [f.relative_to(_ROOT).as_posix(), f.read_bytes()]
            _VERSION.append(cache.digest(*parts))
        except OSError:
            _VERSION.append(None)
    return _VERSION[0]


def usable() -> bool:
    """Whether the cache is on (a folder, :mod:`doodle.core.cache`) and the code's version known."""
    return cache.folder() is not None and code_version() is not None


def _header(arrays: dict, kind: str, key: str) -> dict:
    """The JSON header of an entry, checked to be the one asked for (else ValueError)."""
    meta = json.loads(str(arrays["meta"][()]))
    if meta.get("format") != FORMAT or meta.get("kind") != kind or meta.get("key") != key:
        raise ValueError("another entry")
    return meta


def _meta(kind: str, key: str, **fields) -> np.ndarray:
    return np.array(json.dumps({"format": FORMAT, "kind": kind, "key": key, **fields}))


def _joined(kind: str, parts: dict, dtypes: dict) -> tuple[dict, dict]:
    """Each field's arrays (``{field: [array, ...]}``) flattened into one array named
    ``KIND_FIELD`` (a few large archive members read faster than many small ones), and the
    arrays' shapes (``{field: [shape, ...]}``, for the JSON header)."""
    arrays, shapes = {}, {}
    for name, pieces in parts.items():
        pieces = [np.asarray(a, dtype=dtypes[name]) for a in pieces]
        arrays[f"{kind}_{name}"] = np.concatenate([a.reshape(-1) for a in pieces] + [np.zeros(0, dtypes[name])])
        shapes[name] = [list(a.shape) for a in pieces]
    return arrays, shapes


def _split(arrays: dict, kind: str, shapes: dict, dtypes: dict) -> dict:
    """What :func:`_joined` joined: ``{field: [array, ...]}`` of the ``shapes`` given, each
    a view of the field's array; ValueError unless the arrays are exactly that long and of
    the ``dtypes`` given."""
    out = {}
    for name, dtype in dtypes.items():
        flat, listed = arrays[f"{kind}_{name}"], shapes[name]
        if not all(isinstance(s, list) and all(type(n) is int and n >= 0 for n in s) for s in listed):
            raise ValueError(f"{kind} {name}: shapes")
        ends = list(accumulate((prod(s) for s in listed), initial=0))
        if flat.dtype != dtype or flat.shape != (ends[-1],):
            raise ValueError(f"{kind} {name}: size")
        out[name] = [flat[a:b].reshape(s) for a, b, s in zip(ends[:-1], ends[1:], listed)]
    return out


# --- automata ---------------------------------------------------------------------------------

def _expressions(library) -> list[str]:
    return sorted({a.expression for a in library.actions if a.expression.strip()})


def read_dfas(library) -> tuple[str, dict]:
    """``(key, {expression: DFA})``: the library's automata found in the cache (empty when
    none are)."""
    from doodle.core.tokens import N_CODES
    from grammar.automata import DFA

    expressions = _expressions(library)
    key = cache.digest("dfas", code_version(), *expressions)
    arrays = cache.read("dfas", key)
    if arrays is None:
        return key, {}
    try:
        meta = _header(arrays, "dfas", key)
        if meta["expressions"] != expressions:
            raise ValueError("other expressions")
        parts = _split(arrays, "dfas", meta["shapes"], {"table": np.int64, "accept": bool})
        known = {}
        for text, table, accept in zip(expressions, parts["table"], parts["accept"], strict=True):
            if (table.dtype != np.int64 or table.ndim != 2 or table.shape[1] != N_CODES or accept.dtype != bool
                    or accept.shape != (len(table),) or len(table) == 0 or table.min() < -1
                    or table.max() >= len(table)):
                raise ValueError("not a DFA")
            known[text] = DFA(table, accept)
        return key, known
    except (KeyError, ValueError, TypeError, AttributeError):
        return key, {}


def write_dfas(key: str, compiled) -> None:
    """Store the DFAs of ``compiled`` (and of its interaction roles) under ``key``."""
    by_text = {}
    for part in (compiled, compiled.roles):
        if part is not None:
            by_text.update({a.expression: d for a, d in zip(part.library.actions, part.dfas)})
    expressions = sorted(by_text)
    arrays, shapes = _joined("dfas", {"table": [by_text[text].table for text in expressions],
                                      "accept": [by_text[text].accept for text in expressions]},
                             {"table": np.int64, "accept": bool})
    arrays["meta"] = _meta("dfas", key, expressions=expressions, shapes=shapes)
    cache.write("dfas", key, arrays)


class AutomatonStore:
    """The Matcher's tables of a compiled library kept in the cache
    (:attr:`grammar.library.Compiled.store`)."""

    def get(self, compiled, key: tuple, build):
        name = cache.digest("automaton", code_version(), repr(compiled.library.actions), repr(key))
        arrays = cache.read("automaton", name)
        if arrays is not None:
            try:
                _header(arrays, "automaton", name)
                return compiled.automaton_from(key, arrays)
            except (KeyError, ValueError, TypeError, AttributeError, IndexError):
                pass
        automaton = build()
        if automaton is not None:
            cache.write("automaton", name, {"meta": _meta("automaton", name), **automaton.tables()})
        return automaton


def compile_library(library):
    """:func:`grammar.library.compile_library` with the automata kept in the cache: the
    DFAs read back (compiled and stored when missing) and the Matcher's tables stored as
    they are first built. Without a cache folder (``DOODLE_NO_CACHE``), just compiled."""
    from grammar.library import compile_library as compile_

    if not usable():
        return compile_(library)
    key, known = read_dfas(library)
    compiled = compile_(library, known)
    if not known:
        write_dfas(key, compiled)
    return replace(compiled, store=AutomatonStore())


def compiled_actions(library_dir=None, use_builtin: bool = True):
    """The built-in library, extended or overridden by the one in ``library_dir``, compiled
    (:func:`grammar.recognizer.load_actions`, through the cache)."""
    from library.manifest import load_combined

    return compile_library(load_combined(library_dir, use_builtin)[0])


# --- clips ------------------------------------------------------------------------------------

def clips_key(library, user, use_builtin: bool) -> str | None:
    """The key of a library's analysed clips: its definitions, the user library's and the
    built-in one's, and the contents of every file they name; None when a file cannot be
    read (the compile then reports it)."""
    from library.manifest import builtin

    parts = ["clips", code_version(), np.__version__, repr(library), repr(user), use_builtin]
    libraries = [library] + ([user] if user is not None else [])
    if use_builtin and user is not None:
        base = builtin()
        parts.append(repr(base))
        libraries.append(base)
    names = set()
    for lib in libraries:
        for a in lib.actions:
            names.update(a.clips)
            if a.shape:
                names.add(a.shape)
        for i in lib.interactions:
            names.update(i.pair)
    try:
        for name in sorted(names):
            parts += [name, Path(name).read_bytes()]
    except OSError:
        return None
    return cache.digest(*parts)


def _clip_meta(clip) -> dict:
    sk = clip.motion.skeleton
    st = clip.stages
    return {"action": clip.action, "path": clip.path, "roles": {r: int(j) for r, j in clip.roles.items()},
            "stages": [int(v) for v in (st.preparation, st.anticipation, st.execution, st.follow_through,
                                        st.transition)],
            "cycle_length": None if clip.cycle_length is None else float(clip.cycle_length),
            "travel": None if clip.travel is None else float(clip.travel), "retargeted": bool(clip.retargeted),
            "frame_time": float(clip.motion.frame_time), "names": list(sk.names),
            "channels": [list(c) for c in sk.channels], "end_sites": [int(j) for j in sk.end_sites]}


@dataclass(frozen=True)
class Note:
    """A warning given while the clips were analysed, kept with them so that a run reading
    them from the cache says it too (as it was shown: message, category, where)."""

    message: str
    category: str  # module:qualified name
    filename: str
    lineno: int

    @classmethod
    def of(cls, w: warnings.WarningMessage) -> "Note":
        c = w.category
        return cls(str(w.message), f"{c.__module__}:{c.__qualname__}", str(w.filename), int(w.lineno))

    def warn(self) -> None:
        module, _, name = self.category.partition(":")
        try:
            category = getattr(importlib.import_module(module), name)
            if not (isinstance(category, type) and issubclass(category, Warning)):
                raise TypeError
        except (ImportError, AttributeError, TypeError, ValueError):
            category = UserWarning
        warnings.warn_explicit(self.message, category, self.filename, self.lineno)


_CLIP_FIELDS = {"parents": np.int64, "offsets": float, "end_sites": float, "translations": float, "rotations": float,
                "contacts": bool}  # each clip's arrays, and their types in the cache


def write_clips(key: str, clips: dict, directions: dict, said: list = ()) -> None:
    """Store a library's analysed clips (``{action: [Clip]}``), travel directions and the
    warnings given while analysing them (:class:`Note`)."""
    listed, parts = {}, {name: [] for name in _CLIP_FIELDS}
    for action, found in clips.items():
        listed[action] = []
        for clip in found:
            sk, m = clip.motion.skeleton, clip.motion
            listed[action].append(_clip_meta(clip))
            parts["parents"].append(sk.parents)
            parts["offsets"].append(sk.offsets)
            parts["end_sites"].append(np.array([sk.end_sites[j] for j in sk.end_sites], dtype=float).reshape(-1, 3))
            parts["translations"].append(m.translations)
            parts["rotations"].append(m.rotations)
            parts["contacts"].append(clip.contacts)
    arrays, shapes = _joined("clips", parts, _CLIP_FIELDS)
    arrays["meta"] = _meta("clips", key, clips=listed, directions={a: float(v) for a, v in directions.items()},
                           said=[asdict(n) for n in said], shapes=shapes)
    cache.write("clips", key, arrays)


def read_clips(key: str) -> tuple[dict, dict, list] | None:
    """``(clips, directions, warnings)`` as :func:`write_clips` stored them, or None."""
    from retarget.analysis import Stages
    from retarget.clips import Clip
    from retarget.skeleton import Motion, Skeleton

    arrays = cache.read("clips", key)
    if arrays is None:
        return None
    try:
        meta = _header(arrays, "clips", key)
        parts = _split(arrays, "clips", meta["shapes"], _CLIP_FIELDS)
        if any(len(p) != sum(len(listed) for listed in meta["clips"].values()) for p in parts.values()):
            raise ValueError("clips")
        clips, k = {}, 0
        for action, listed in meta["clips"].items():
            clips[action] = []
            for c in listed:
                ends = parts["end_sites"][k]
                if ends.shape != (len(c["end_sites"]), 3):
                    raise ValueError("end sites")
                sk = Skeleton(tuple(c["names"]), parts["parents"][k], parts["offsets"][k],
                              tuple(tuple(ch) for ch in c["channels"]), dict(zip(c["end_sites"], ends)))
                motion = Motion(sk, parts["translations"][k], parts["rotations"][k], c["frame_time"])
                contacts = parts["contacts"][k]
                if contacts.shape != (motion.frames, 2) or contacts.dtype != bool:
                    raise ValueError("contacts")
                clips[action].append(Clip(c["action"], c["path"], motion, dict(c["roles"]), Stages(*c["stages"]),
                                          c["cycle_length"], contacts, c["travel"], c["retargeted"]))
                k += 1
        said = [Note(str(n["message"]), str(n["category"]), str(n["filename"]), int(n["lineno"]))
                for n in meta["said"]]
        return clips, dict(meta["directions"]), said
    except (KeyError, ValueError, TypeError, AttributeError, IndexError):
        return None
