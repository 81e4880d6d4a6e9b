"""Open any supported doodle input by its file name: ``.doodle`` files or plain CSV.

A doodle file names its own convention in its header; a CSV does not, so the caller must
say which one it uses (a wrong guess silently mirrors left and right, hence no default).
Device mounts (profile, then calibration) turn device orientations into figurine ones.
"""

from __future__ import annotations

from pathlib import Path

from doodle.input.devices import mount_doodle, profile
from doodle.core.errors import DoodleError
from doodle.input.fileformat import read_doodle
from doodle.core.model import Doodle


def load(path, convention: str | None = None, columns: dict | None = None,
         tracks: list[str] | None = None, mounts: dict[str, tuple] | None = None, raw: bool = False) -> Doodle:
    """Read ``path`` into our frame and keep ``tracks`` (all when None).

    Orientations become figurine orientations through the device profile's mount, or the
    ``mounts`` given (track → device-to-figurine quaternion, from calibration); ``raw=True``
    keeps device orientations as read (for converting files).
    """
    path = Path(path)
    if not path.exists():
        raise DoodleError(f"{path}: no such file")
    if path.is_dir():
        raise DoodleError(f"{path}: is a directory, not a doodle file")
    if path.suffix.lower() == ".csv":
        if convention is None:
            raise DoodleError(
                f"{path}: a CSV file does not say its coordinate convention; name it: unity, openvr or doodle"
            )
        from doodle.input.csvimport import read_csv  # here: a doodle file needs no CSV reader

        doodle = read_csv(path, convention=convention, columns=columns)
    else:
        if convention is not None:
            raise DoodleError(f"{path}: a doodle file's header names its own convention; one is given only for CSV input")
        doodle = read_doodle(path)
    doodle = doodle.select(tracks)
    if raw:
        return doodle
    base = {tr.name: profile(doodle.device).mount for tr in doodle.tracks}
    return mount_doodle(doodle, {**base, **(mounts or {})})
