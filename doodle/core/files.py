"""Files written whole or not at all: a temporary file beside the target, renamed over it."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Iterable, Iterator

from doodle.core.errors import DoodleError


@contextlib.contextmanager
def atomic_path(path) -> Iterator[str]:
    """Yield the name of a temporary file beside ``path`` (same suffix, so writers that go by
    it pick the right format) and rename it to ``path`` when the block succeeds, keeping an
    existing file's mode. On any exception the temporary file is removed, an existing
    ``path`` is untouched, and the exception propagates (OSError becomes DoodleError)."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix or ".tmp", dir=directory)
    except OSError as exc:
        raise DoodleError(f"{path}: cannot write: {exc.strerror or exc}") from None
    os.close(fd)
    try:
        yield tmp
        try:
            mode = os.stat(path).st_mode & 0o777
        except OSError:
            mode = 0o644
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except OSError as exc:
        raise DoodleError(f"{path}: cannot write: {exc.strerror or exc}") from None
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def atomic_write(path, chunks: Iterable[str] | bytes) -> None:
    """Write the text ``chunks`` (or one ``bytes``) to ``path`` atomically (:func:`atomic_path`),
    synced to the disk before the rename."""
    binary = isinstance(chunks, bytes)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") if binary else open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            for text in [chunks] if binary else chunks:
                fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
