"""Wavefront OBJ meshes read by our own small parser, so that a broken file is an error naming
its line — trimesh's reader answers a junk OBJ with numpy's own complaints (operands that
cannot be broadcast, literals that are not ints) or silently drops what it cannot read.

Only geometry matters to a terrain: ``v x y z [w]`` (or ``v x y z r g b`` with vertex
colours) and ``f`` polygons of vertex references ``i``, ``i/t``, ``i//n`` or ``i/t/n``
(1-based, or negative: counted back from the latest vertex), split into a fan of triangles.
Every other statement of the OBJ specification (texture coordinates, normals, groups,
materials, smoothing, curves and surfaces) is skipped; a statement outside it is an error,
so that a file that is not an OBJ at all is refused at its first line.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from doodle.core.errors import DoodleError, where

#: Statements of the OBJ specification a terrain does not need.
SKIPPED = frozenset(
    "vt vn vp l p o g s mg usemtl mtllib maplib usemap lod bevel c_interp d_interp shadow_obj trace_obj "
    "ctech stech cstype deg bmat step curv curv2 surf parm trim hole scrv sp end con".split())


def _lines(text: str):
    """``(line number, words)`` of each statement: comments, blank lines and ``\\`` line
    continuations handled."""
    pending, first = [], 0
    for number, line in enumerate(text.split("\n"), 1):
        line = line.split("#", 1)[0].rstrip("\r")
        if not pending:
            first = number
        if line.rstrip().endswith("\\"):
            pending.append(line.rstrip()[:-1])
            continue
        words = " ".join(pending + [line]).split()
        pending = []
        if words:
            yield first, words
    if pending and " ".join(pending).split():
        yield first, " ".join(pending).split()


def _vertex(words: list[str], place: str, limit: float) -> list[float]:
    if len(words) not in (4, 5, 7, 8):
        raise DoodleError(f"{place}: a vertex is 'v x y z' (optionally w, or r g b), got {len(words) - 1} values")
    xyz = []
    for word in words[1:4]:
        try:
            value = float(word)
        except ValueError:
            raise DoodleError(f"{place}: vertex coordinate {word!r} is not a number") from None
        if not math.isfinite(value) or abs(value) > limit:
            raise DoodleError(f"{place}: vertex coordinate {word} is not a finite number within ±{limit:g} m")
        xyz.append(value)
    return xyz


def _face(words: list[str], place: str, count: int) -> list[int]:
    if len(words) < 4:
        raise DoodleError(f"{place}: a face needs at least 3 vertices, got {len(words) - 1}")
    out = []
    for word in words[1:]:
        head = word.split("/", 1)[0]
        try:
            i = int(head)
        except ValueError:
            raise DoodleError(f"{place}: face vertex {word!r} is not a vertex number") from None
        k = i - 1 if i > 0 else count + i
        if i == 0 or not 0 <= k < count:
            raise DoodleError(f"{place}: face vertex {i} does not exist ({count} vertices so far)")
        out.append(k)
    return out


def read_obj(path, limit: float = math.inf) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V, 3), faces (F, 3))`` of the OBJ file at ``path``; coordinates beyond
    ``±limit`` are refused. Raises DoodleError naming the file and line of the first problem."""
    path = Path(path)
    source = str(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        line = exc.object.count(b"\n", 0, exc.start) + 1
        raise DoodleError(f"{where(source, line)}: not an OBJ text file (byte {exc.start} is not UTF-8)") from None
    except OSError as exc:
        raise DoodleError(f"{source}: cannot read: {exc.strerror or exc}") from None
    vertices: list[list[float]] = []
    faces: list[list[int]] = []
    for number, words in _lines(text):
        keyword, place = words[0], where(source, number)
        if keyword == "v":
            vertices.append(_vertex(words, place, limit))
        elif keyword == "f":
            polygon = _face(words, place, len(vertices))
            faces.extend([polygon[0], polygon[k], polygon[k + 1]] for k in range(1, len(polygon) - 1))
        elif keyword not in SKIPPED:
            raise DoodleError(f"{place}: {keyword[:20]!r} is not an OBJ statement (not an OBJ file?)")
    if not faces:
        raise DoodleError(f"{source}: has no faces (no 'f' lines)")
    return np.array(vertices, dtype=float).reshape(-1, 3), np.array(faces, dtype=np.intp).reshape(-1, 3)
