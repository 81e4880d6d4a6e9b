"""A disk cache of work derived from files (the analysed clips and compiled automata of an
action library: :mod:`doodle.app.libcache`), so a second run does not redo it.

* **Where**: ``$DOODLE_CACHE`` if set, else ``$XDG_CACHE_HOME/doodle``, else
  ``~/.cache/doodle``. ``DOODLE_NO_CACHE=1`` (``doodle compile --no-cache``) turns it off:
  nothing is read or written.
* **What**: one ``.npz`` of plain arrays per entry, a JSON header among them — written with
  numpy, read with :func:`doodle.core.npz.read_npz` (never a pickle).
* **Keys**: an entry is named by a hash (:func:`digest`) of everything it is derived from —
  the files' contents, the code that derived it, a format number — so a change of any of
  them is a new name, and an entry is never updated in place.
* **Safe**: written atomically (a temporary file renamed over the name:
  :func:`doodle.core.files.atomic_write`), so a reader never sees half an entry; a missing,
  truncated or corrupt entry reads as absent (and is rebuilt by the caller); a folder that
  cannot be made or written is skipped. Entries are not synced to the disk before the
  rename (an output is): one a power cut empties reads as absent, and a first run does not
  wait on the disk. The cache can only make a run faster, never fail
  it — and the folder can be deleted at any time.
* **Size**: the :data:`KEEP` most recently used entries are kept, older ones removed when
  a new one is written. Entries are named ``doodle-KIND-HASH.npz``; nothing else in the
  folder is ever touched.
"""

from __future__ import annotations

import hashlib
import io
import os
import re
from pathlib import Path

KEEP = 16  # entries kept (a built-in library's is ~5 MB)
_NAME = re.compile(r"^doodle-[a-z]+-[0-9a-f]{64}\.npz$")


def folder() -> Path | None:
    """The cache folder, or None when caching is turned off (``DOODLE_NO_CACHE``)."""
    if os.environ.get("DOODLE_NO_CACHE", "").strip() not in ("", "0"):
        return None
    given = os.environ.get("DOODLE_CACHE", "").strip()
    if given:
        return Path(given).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME", "").strip()
    base = Path(xdg) if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return base / "doodle"


def digest(*parts) -> str:
    """A hex SHA-256 of ``parts`` (bytes, or anything whose ``str`` says what it is), each
    length-prefixed so that no two sequences of parts collide by concatenation."""
    h = hashlib.sha256()
    for part in parts:
        data = part if isinstance(part, bytes) else str(part).encode("utf-8", "surrogatepass")
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()


def _path(kind: str, key: str) -> Path | None:
    where = folder()
    name = f"doodle-{kind}-{key}.npz"
    if not _NAME.match(name):
        raise ValueError(f"not a cache entry name: {name!r}")
    return None if where is None else where / name


def read(kind: str, key: str) -> dict | None:
    """The arrays of the entry of ``kind`` (lower-case letters) and ``key`` (a
    :func:`digest`), or None when it is absent, unreadable or corrupt (or caching is off). A
    hit marks the entry as recently used."""
    path = _path(kind, key)
    if path is None or not path.is_file():
        return None
    from doodle.core.errors import DoodleError
    from doodle.core.npz import read_npz

    try:
        arrays = read_npz(path)
    except (DoodleError, OSError, MemoryError):
        return None
    try:
        os.utime(path)
    except OSError:
        pass
    return arrays


def write(kind: str, key: str, arrays: dict) -> bool:
    """Store ``arrays`` (plain numpy arrays, no objects) as the entry of ``kind`` and
    ``key``, atomically; False when caching is off or the folder cannot be written (never an
    error)."""
    path = _path(kind, key)
    if path is None:
        return False
    import numpy as np

    from doodle.core.errors import DoodleError
    from doodle.core.files import atomic_write

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        atomic_write(path, buf.getvalue(), sync=False)  # lost in a power cut: unreadable, so rebuilt
    except (DoodleError, OSError, ValueError):
        return False
    prune(path.parent)
    return True


def prune(where: Path, keep: int = KEEP) -> None:
    """Remove all but the ``keep`` most recently used entries (``doodle-KIND-HASH.npz``) of
    the folder ``where``."""
    try:
        entries = [(p.stat().st_mtime, p) for p in where.iterdir() if _NAME.match(p.name) and p.is_file()]
    except OSError:
        return
    for _, p in sorted(entries, reverse=True)[keep:]:
        try:
            p.unlink()
        except OSError:
            pass
