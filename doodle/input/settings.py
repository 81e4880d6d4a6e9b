"""Calibration files: Segmenter thresholds and per-track mounts, as TOML.

```toml
# written by `doodle calibrate`
[segmenter]
eps = 0.05      # m/s
theta = 0.3     # m/rad

[mount]         # device-to-figurine quaternion (x, y, z, w) per track
c0 = [0.0, 0.0, 0.0, 1.0]
```
Every key is optional; unknown keys are errors naming the file and the key.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import fields, replace
from pathlib import Path

from doodle.core.errors import DoodleError
from doodle.core.files import atomic_write
from doodle.input.segmenter import SegmenterParams

_NUMERIC = {f.name for f in fields(SegmenterParams) if f.name != "smoothing"}


def read_calibration(path, params: SegmenterParams = SegmenterParams()) -> tuple[SegmenterParams, dict[str, tuple]]:
    """``(params, mounts)`` from a calibration file, starting from ``params``."""
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as e:
        raise DoodleError(f"{path}: cannot read calibration: {e.strerror or e}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise DoodleError(f"{path}: not valid TOML: {e}") from None
    unknown = set(data) - {"segmenter", "mount"}
    if unknown:
        raise DoodleError(f"{path}: unknown section [{sorted(unknown)[0]}] (known: segmenter, mount)")
    for section in ("segmenter", "mount"):
        if not isinstance(data.get(section, {}), dict):
            raise DoodleError(f"{path}: [{section}] must be a table")
    seg = data.get("segmenter", {})
    changes = {}
    for key, value in seg.items():
        if key == "smoothing" and value in ("laplacian", "savgol"):
            changes[key] = value
        elif key in _NUMERIC and isinstance(value, (int, float)) and not isinstance(value, bool):
            changes[key] = float(value)
        else:
            raise DoodleError(f"{path}: segmenter.{key}: unknown key or bad value {value!r}")
    try:
        params = replace(params, **changes)
    except DoodleError as e:
        raise DoodleError(f"{path}: {e}") from None
    mounts = {}
    for name, value in data.get("mount", {}).items():
        ok = isinstance(value, list) and len(value) == 4 and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and abs(x) <= 2.0 for x in value)
        norm = math.sqrt(sum(float(x) ** 2 for x in value)) if ok else 0.0
        if not ok or abs(norm - 1.0) > 0.01:
            raise DoodleError(f"{path}: mount.{name}: expected a unit quaternion [x, y, z, w], got {value!r}")
        mounts[name] = tuple(float(x) / norm for x in value)
    return params, mounts


def write_calibration(path, params: SegmenterParams, mounts: dict[str, tuple]) -> None:
    lines = ["# written by `doodle calibrate`", "[segmenter]", f"eps = {params.eps:.6g}  # m/s",
             f"theta = {params.theta:.6g}  # m/rad", ""]
    if mounts:
        lines.append("[mount]  # device-to-figurine quaternion (x, y, z, w) per track")
        lines += [f"{name} = [{', '.join(f'{x:.6f}' for x in q)}]" for name, q in mounts.items()]
    atomic_write(path, ["\n".join(lines) + "\n"])
