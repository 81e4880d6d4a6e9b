"""A library folder changed whole or not at all.

`doodle library import` and `doodle learn` write several files into a library (the
manifest, clips, shapes). Written one by one, a failure or a kill half-way would leave a
manifest naming files of another version, or a new manifest beside a broken clip: the
library is built in a staging folder beside it and swapped in when complete
(:func:`doodle.core.files.atomic_folder`). Only a folder that is new, empty, a library, or
holding nothing but what doodle puts into one is replaced: ``-o ~`` must not swap a home
folder for a library.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Iterable, Iterator

from doodle.core.errors import DoodleError
from doodle.core.files import atomic_folder, check_dir

MANIFEST = "library.toml"
MANAGED = {MANIFEST, "clips", "shapes", "takes"}  # what doodle puts into a library folder


def check_library_folder(folder) -> Path:
    """``folder`` as a library to write: missing, empty, a library, or holding nothing but
    doodle's own (``clips``, ``shapes``, ``takes``); a DoodleError naming it otherwise."""
    folder = check_dir(folder)
    if folder.is_dir() and not (folder / MANIFEST).exists():
        other = sorted(e.name for e in os.scandir(folder) if e.name not in MANAGED and not e.name.startswith("."))
        if other:
            raise DoodleError(f"{folder}: is a folder but not a library (no {MANIFEST}; it holds {other[0]!r}"
                              f"{' and more' if len(other) > 1 else ''}); give a new folder or a library's")
    return folder


@contextlib.contextmanager
def updating(folder, fresh: Iterable[str] = ()) -> Iterator[Path]:
    """A staging copy of the library ``folder`` (less the top-level names in ``fresh``) to
    write the new version into; swapped in for ``folder`` when the block succeeds, ``folder``
    left as it was when it fails."""
    check_library_folder(folder)
    with atomic_folder(folder, fresh) as stage:
        yield stage
