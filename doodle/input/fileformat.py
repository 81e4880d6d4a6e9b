"""The doodle file format, version 1: a line-oriented, append-friendly UTF-8 text file.

Layout::

    # doodle 1
    # device vive-controller
    # rate 90
    # units m
    # convention openvr
    # track c0 role=right_hand serial=LHR-1A2B3C4D
    # track c1 role=left_hand
    # x-note any free text
    t,c0.ok,c0.px,c0.py,c0.pz,c0.qx,c0.qy,c0.qz,c0.qw,c1.ok,c1.px,...
    0.000000,1,0.258747,0.378101,-0.036361,0.393373,-0.011139,0.107187,0.913041,1,...

- Line 1 is exactly ``# doodle 1`` (magic and format version).
- Header lines ``# KEY VALUE``: ``device`` (text), ``rate`` (nominal Hz, 1 to 1000), ``units``
  (``m``, ``cm`` or ``mm``; positions are converted to metres on load), ``convention`` (a
  name of :data:`doodle.input.conventions.CONVENTIONS`), and one ``track NAME [role=R]
  [serial=S]`` per track (names unique, ``[A-Za-z0-9_-]+``). All of these are required
  (at least one track). Keys starting ``x-`` are free metadata kept in ``Doodle.meta``.
- Then the column line: ``t`` and, per track in header order, ``NAME.ok``, ``NAME.px``,
  ``NAME.py``, ``NAME.pz``, ``NAME.qx``, ``NAME.qy``, ``NAME.qz``, ``NAME.qw``.
- Then one comma-separated row per sample. ``t`` is in seconds, finite and strictly
  increasing (any origin). ``ok`` is 1 (tracked: all 7 values finite, quaternion xyzw of
  norm within 0.1 of 1, renormalised on load) or 0 (lost tracking: values are ``nan`` or
  any finite number, and load as NaN).
- A recording cut off mid-line (a crash) loads up to its last whole row, with a warning.

On load, ``Track.t`` is ``t - t[0]``: seconds from the first sample, whatever origin the
file's timestamps use (the absolute origin is not kept). Poses are converted from the
file's convention and units to ours (metres, see :mod:`doodle.input.conventions`). All tracks of
a loaded doodle share one ``t`` array.
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path
from typing import Iterable, Iterator

import numpy as np

from doodle.input.conventions import CONVENTIONS, from_ours, to_ours
from doodle.core.errors import DoodleError, where
from doodle.core.files import atomic_write
from doodle.core.model import Doodle, Track
from doodle.input.repair import drop_impossible

VERSION = 1
SUPPORTED_VERSIONS = (1,)
MAGIC = f"# doodle {VERSION}"
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}  # metres per unit
FIELDS = ("ok", "px", "py", "pz", "qx", "qy", "qz", "qw")
REQUIRED = ("device", "rate", "units", "convention")
NAME_RE = re.compile(r"[A-Za-z0-9_-]+")
QUAT_NORM_TOL = 0.1
MIN_RATE, MAX_RATE = 1.0, 1000.0  # Hz a tracker may sample at: kernels in seconds stay a sane size
MAX_TIME = 1e12  # s: beyond any clock's seconds (30 000 years), and differences of times stay finite
SYNC_EVERY_S = 1.0  # DoodleWriter: flush + fsync at most this often (sample time)


# --------------------------------------------------------------------------- header


def column_names(track_names: Iterable[str]) -> list[str]:
    """The column line's names for tracks in this order: ``t``, then ``NAME.ok`` … ``NAME.qw``."""
    cols = ["t"]
    for name in track_names:
        cols += [f"{name}.{f}" for f in FIELDS]
    return cols


def _check_token(value: str, what: str) -> str:
    if not value or any(c.isspace() for c in value) or "," in value:
        raise DoodleError(f"{what} {value!r} must be non-empty, without spaces or commas")
    return value


def format_header(
    tracks: list[tuple[str, str, str]],
    rate: float,
    device: str,
    convention: str = "doodle",
    units: str = "m",
    meta: dict | None = None,
) -> str:
    """The header lines and the column line, each ending in a newline.

    ``tracks`` is a list of ``(name, role, serial)``. Meta keys not starting ``x-`` get that
    prefix (a collision with an existing ``x-`` key is dropped); newlines in values become
    spaces. Raises DoodleError for a bad track name, role or serial, duplicate names, a rate
    that is not a finite number > 0, unknown units or convention, or an empty device.
    """
    if convention not in CONVENTIONS:
        raise DoodleError(f"unknown coordinate convention {convention!r} (known: {', '.join(sorted(CONVENTIONS))})")
    if units not in UNITS:
        raise DoodleError(f"unknown units {units!r} (known: {', '.join(UNITS)})")
    rate = float(rate)
    if not MIN_RATE <= rate <= MAX_RATE:
        raise DoodleError(f"rate must be a number from {MIN_RATE:g} to {MAX_RATE:g} Hz, got {rate}")
    device = " ".join(str(device).split())
    if not device:
        raise DoodleError("device must not be empty")
    if not tracks:
        raise DoodleError("a doodle file needs at least one track")
    lines = [MAGIC, f"# device {device}", f"# rate {rate:.12g}", f"# units {units}", f"# convention {convention}"]
    seen = set()
    for name, role, serial in tracks:
        if not NAME_RE.fullmatch(name or ""):
            raise DoodleError(f"track name {name!r} must match [A-Za-z0-9_-]+")
        if name in seen:
            raise DoodleError(f"duplicate track name {name!r}")
        seen.add(name)
        line = f"# track {name}"
        if role:
            line += f" role={_check_token(role, f'track {name}: role')}"
        if serial:
            line += f" serial={_check_token(serial, f'track {name}: serial')}"
        lines.append(line)
    written = set()
    for key, value in (meta or {}).items():
        key = str(key) if str(key).startswith("x-") else f"x-{key}"
        _check_token(key[2:], "meta key")
        if key in written:
            continue
        written.add(key)
        text = " ".join(str(value).splitlines()).strip()
        lines.append(f"# {key} {text}" if text else f"# {key}")
    lines.append(",".join(column_names(n for n, _, _ in tracks)))
    return "\n".join(lines) + "\n"


def _parse_track(value: str, source: str, line: int, names: set) -> tuple[str, str, str]:
    parts = value.split()
    if not parts:
        raise DoodleError(f"{where(source, line)}: track line without a name")
    name, attrs = parts[0], {}
    if not NAME_RE.fullmatch(name):
        raise DoodleError(f"{where(source, line)}: track name {name!r} must match [A-Za-z0-9_-]+")
    if name in names:
        raise DoodleError(f"{where(source, line)}: duplicate track {name!r}")
    for part in parts[1:]:
        key, eq, val = part.partition("=")
        if not eq or key not in ("role", "serial"):
            raise DoodleError(f"{where(source, line)}: track {name}: expected role=… or serial=…, got {part!r}")
        if key in attrs:
            raise DoodleError(f"{where(source, line)}: track {name}: duplicate {key}")
        attrs[key] = val
    return name, attrs.get("role", ""), attrs.get("serial", "")


def _check_magic(first: str, source: str) -> None:
    if first == MAGIC:
        return
    m = re.fullmatch(r"#\s*doodle\s+(\S+)\s*", first)
    if m:
        supported = ", ".join(str(v) for v in SUPPORTED_VERSIONS)
        raise DoodleError(
            f"{where(source, 1)}: doodle format version {m.group(1)} is not supported (supported: {supported})"
        )
    raise DoodleError(f"{where(source, 1)}: not a doodle file (the first line must be {MAGIC!r})")


def parse_header(lines: list[str], source: str) -> tuple[dict, int]:
    """Parse the header of a doodle file given as its lines (without newlines).

    Returns ``(header, k)``: ``header`` has ``device`` (str), ``rate`` (float), ``units``,
    ``convention``, ``tracks`` (list of ``(name, role, serial)``) and ``meta`` (dict of the
    ``x-`` keys); ``k`` is the number of header lines (the column line is ``lines[k]``).
    Raises DoodleError naming the file and line for a bad magic or version, an unknown,
    duplicate, missing or malformed key, or a header that never ends.
    """
    if not lines:
        raise DoodleError(f"{source}: empty file, not a doodle file")
    _check_magic(lines[0], source)
    header: dict = {"tracks": [], "meta": {}}
    names: set = set()
    k = 1
    while k < len(lines) and lines[k].startswith("#"):
        lineno = k + 1
        key, value = (lines[k][1:].split(None, 1) + ["", ""])[:2]
        value = value.strip()
        if key == "track":
            track = _parse_track(value, source, lineno, names)
            names.add(track[0])
            header["tracks"].append(track)
        elif key.startswith("x-") and len(key) > 2:
            if key in header["meta"]:
                raise DoodleError(f"{where(source, lineno)}: duplicate header key {key!r}")
            header["meta"][key] = value
        elif key in REQUIRED:
            if key in header:
                raise DoodleError(f"{where(source, lineno)}: duplicate header key {key!r}")
            header[key] = _parse_value(key, value, source, lineno)
        else:
            known = ", ".join(REQUIRED + ("track", "x-…"))
            raise DoodleError(f"{where(source, lineno)}: unknown header key {key!r} (known: {known})")
        k += 1
    if k >= len(lines):
        raise DoodleError(f"{where(source, k)}: file ends in the header (no column line)")
    for key in REQUIRED:
        if key not in header:
            raise DoodleError(f"{where(source, k + 1)}: header lacks the required key {key!r}")
    if not header["tracks"]:
        raise DoodleError(f"{where(source, k + 1)}: header declares no track (need at least one '# track NAME')")
    return header, k


def _parse_value(key: str, value: str, source: str, line: int):
    place = where(source, line)
    if not value:
        raise DoodleError(f"{place}: header key {key!r} has no value")
    if key == "device":
        return value
    if key == "rate":
        try:
            rate = float(value)
        except ValueError:
            rate = float("nan")
        if not MIN_RATE <= rate <= MAX_RATE:
            raise DoodleError(f"{place}: rate must be a number from {MIN_RATE:g} to {MAX_RATE:g} (Hz), got {value!r}")
        return rate
    if key == "units":
        if value not in UNITS:
            raise DoodleError(f"{place}: units must be one of {', '.join(UNITS)}, got {value!r}")
        return value
    if value not in CONVENTIONS:
        raise DoodleError(f"{place}: unknown convention {value!r} (known: {', '.join(sorted(CONVENTIONS))})")
    return value


def check_columns(line: str, expected: list[str], source: str, lineno: int) -> None:
    """Raise DoodleError naming the first missing, extra or misplaced column of the column line."""
    got = [c.strip() for c in line.split(",")]
    if got == expected:
        return
    place = where(source, lineno)
    for i, (g, e) in enumerate(zip(got, expected)):
        if g != e:
            if e in got:
                raise DoodleError(f"{place}: column {i + 1} is {g!r}, expected {e!r} (columns out of order?)")
            raise DoodleError(f"{place}: column {i + 1} is {g!r}, expected {e!r} (missing column {e!r})")
    if len(got) < len(expected):
        raise DoodleError(f"{place}: missing column {expected[len(got)]!r}")
    raise DoodleError(f"{place}: unexpected extra column {got[len(expected)]!r}")


# --------------------------------------------------------------------------- rows


def row_format(n_tracks: int) -> str:
    """The %-format of one data row: ``%.6f`` for t and values, ``%d`` for ok."""
    return ",".join(["%.6f"] + ["%d" + ",%.6f" * 7] * n_tracks)


def _is_number(text: str) -> bool:
    """Whether ``np.loadtxt`` reads ``text`` as a number (stricter than ``float``: no ``1_000``,
    no digits of other scripts)."""
    return "," not in text and _is_number_row(text)


def _is_number_row(line: str) -> bool:
    """Whether ``np.loadtxt`` reads every field of ``line``."""
    try:
        np.loadtxt([line], delimiter=",", comments=None, dtype=np.float64)
    except ValueError:
        return False
    return True


def _first_bad_field(line: str, columns: list[str], strict: bool = False) -> tuple[str, str] | None:
    """``(column, text)`` of the first field of ``line`` that is not a number (``strict``: as
    ``np.loadtxt`` reads numbers), else None."""
    for col, text in zip(columns, line.split(",")):
        try:
            float(text)
        except ValueError:
            return col, text
        if strict and not _is_number(text):
            return col, text
    return None


def _line_parses(line: str, columns: list[str]) -> bool:
    return line.count(",") == len(columns) - 1 and _first_bad_field(line, columns, strict=True) is None


def parse_rows(lines: list[str], columns: list[str], source: str, first_line: int) -> np.ndarray:
    """Parse comma-separated data lines into an ``(n, len(columns))`` float array.

    ``first_line`` is the 1-based file line number of ``lines[0]``. Fast path: one
    ``np.loadtxt``; only on failure are the lines scanned one by one to locate the error.
    Raises DoodleError naming file, line and column for a blank line, a wrong field count
    or a value that is not a number.
    """
    want = len(columns) - 1
    counts = np.fromiter((line.count(",") for line in lines), dtype=np.int64, count=len(lines))
    bad = np.flatnonzero(counts != want)
    if bad.size:
        i = int(bad[0])
        place = where(source, first_line + i)
        if not lines[i].strip():
            raise DoodleError(f"{place}: blank line in the data")
        n = counts[i] + 1
        col = columns[n] if n < len(columns) else columns[-1]
        what = f"missing column {col!r}" if n < len(columns) else f"extra field after column {col!r}"
        raise DoodleError(f"{place}: {n} fields, expected {len(columns)} ({what})")
    if not lines:
        return np.empty((0, len(columns)))
    try:
        return np.loadtxt(lines, delimiter=",", comments=None, dtype=np.float64, ndmin=2)
    except ValueError as exc:
        found = _locate_bad_field(lines, columns)
        if found:
            i, col, text = found
            raise DoodleError(f"{where(source, first_line + i, col)}: {text.strip()!r} is not a number") from None
        raise DoodleError(f"{source}: cannot parse the data rows: {exc}") from None


def _locate_bad_field(lines: list[str], columns: list[str]) -> tuple[int, str, str] | None:
    """``(line index, column, text)`` of the first field that is not a number: by ``float``
    first (fast), then as ``np.loadtxt`` reads numbers (no ``1_000``, no digits of other
    scripts), one line at a time."""
    for i, line in enumerate(lines):
        found = _first_bad_field(line, columns)
        if found:
            return (i, *found)
    for i, line in enumerate(lines):
        if not _is_number_row(line):
            found = _first_bad_field(line, columns, strict=True)
            if found:
                return (i, *found)
    return None


# --------------------------------------------------------------------------- checks


def check_finite_or_nan(values: np.ndarray, columns: list[str], source: str, linenos: np.ndarray) -> None:
    """Raise DoodleError naming line and column of the first infinite value in ``values``."""
    inf = np.isinf(values)
    if inf.any():
        i, j = np.argwhere(inf)[0]
        raise DoodleError(f"{where(source, int(linenos[i]), columns[j])}: infinite value")


def check_times(t: np.ndarray, source: str, linenos: np.ndarray, column: str = "t") -> None:
    """Raise DoodleError unless ``t`` is finite and strictly increasing.

    The message names the line (``linenos[i]`` is the file line of row ``i``) and, for a
    time that does not increase, both times.
    """
    nonfinite = np.flatnonzero(~np.isfinite(t))
    if nonfinite.size:
        i = int(nonfinite[0])
        raise DoodleError(f"{where(source, int(linenos[i]), column)}: time {t[i]} is not a finite number")
    huge = np.flatnonzero(np.abs(t) > MAX_TIME)
    if huge.size:
        i = int(huge[0])
        raise DoodleError(f"{where(source, int(linenos[i]), column)}: time {t[i]:g} s is beyond ±{MAX_TIME:g} s "
                          "(seconds are expected)")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = int(back[0]) + 1
        what = "repeats" if t[i] == t[i - 1] else "goes back from"
        raise DoodleError(
            f"{where(source, int(linenos[i]))}: time {t[i]:.6f} {what} the previous row's {t[i - 1]:.6f} "
            f"(line {int(linenos[i - 1])}); times must strictly increase"
        )


def check_count(n: int, source: str) -> None:
    """Raise DoodleError when there are fewer than two samples."""
    if n == 0:
        raise DoodleError(f"{source}: no samples")
    if n == 1:
        raise DoodleError(f"{source}: only one sample; a doodle needs at least two samples")


def check_poses(
    ok: np.ndarray, p: np.ndarray, q: np.ndarray, source: str, linenos: np.ndarray, track: str,
    columns: list[str] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Validate one track's samples and return ``(p, q)`` cleaned.

    Where ``ok``: all 7 values must be finite and the quaternion's norm within 0.1 of 1
    (it is renormalised). Where not ``ok``: values become NaN. Raises DoodleError naming
    file, line and column (``columns``: the 7 names of px … qw in the file, by default
    ``TRACK.px`` … ``TRACK.qw``) otherwise.
    """
    columns = columns or [f"{track}.{f}" for f in FIELDS[1:]]
    p = np.array(p, dtype=float)
    q = np.array(q, dtype=float)
    values = np.concatenate([p, q], axis=1)
    bad = np.argwhere(ok[:, None] & ~np.isfinite(values))
    if bad.size:
        i, j = (int(k) for k in bad[0])
        raise DoodleError(f"{where(source, int(linenos[i]), columns[j])}: track {track}: {values[i, j]} in a "
                          "sample marked tracked (every value of a tracked sample must be a finite number)")
    with np.errstate(over="ignore"):  # a component of 1e200 is a norm of inf: refused below
        norm = np.linalg.norm(np.where(ok[:, None], q, 1.0), axis=1)
    bad = np.flatnonzero(ok & (np.abs(norm - 1.0) > QUAT_NORM_TOL))
    if bad.size:
        i = int(bad[0])
        what = "zero quaternion" if norm[i] == 0 else f"quaternion norm {norm[i]:.4g} is not within {QUAT_NORM_TOL} of 1"
        raise DoodleError(f"{where(source, int(linenos[i]), f'{columns[3]}…{columns[6]}')}: track {track}: {what}")
    q = q / np.where(ok, norm, 1.0)[:, None]
    p[~ok] = np.nan
    q[~ok] = np.nan
    return p, q


# --------------------------------------------------------------------------- reading


def _read_text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DoodleError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise DoodleError(f"{path}: cannot read: {exc.strerror or exc}") from None


def split_lines(text: str) -> tuple[list[str], bool]:
    """``(lines, complete)``: the text's lines without newlines, and whether it ended in one."""
    lines = text.split("\n")
    complete = lines[-1] == ""
    if complete:
        lines.pop()
    return lines, complete


def read_doodle(path) -> Doodle:
    """Load a doodle file (format version 1) into our frame, in metres.

    Returns a Doodle with ``source=str(path)``, the header's device and rate, and the
    ``x-`` header entries in ``meta``; each Track's ``t`` is seconds from the first sample.
    A last line without a newline that does not parse is dropped with a warning
    (``warnings.warn``). Raises DoodleError naming file and line for every problem the
    module docstring lists.
    """
    path = Path(path)
    source = str(path)
    lines, complete = split_lines(_read_text(path))
    header, k = parse_header(lines, source)
    names = [name for name, _, _ in header["tracks"]]
    columns = column_names(names)
    check_columns(lines[k], columns, source, k + 1)
    data = lines[k + 1 :]
    first_line = k + 2
    if data and not complete and not _line_parses(data[-1], columns):
        lineno = first_line + len(data) - 1
        data = data[:-1]
        warnings.warn(f"{path}:{lineno}: last row is incomplete (cut off?); loaded {len(data)} whole rows")
    values = parse_rows(data, columns, source, first_line)
    check_count(len(values), source)
    linenos = first_line + np.arange(len(values))
    check_finite_or_nan(values, columns, source, linenos)
    t = values[:, 0]
    check_times(t, source, linenos)
    scale = UNITS[header["units"]]
    rel_t = t - t[0]
    tracks = []
    for j, (name, role, serial) in enumerate(header["tracks"]):
        c = 1 + 8 * j
        okv = values[:, c]
        notflag = np.flatnonzero((okv != 0) & (okv != 1))
        if notflag.size:
            i = int(notflag[0])
            raise DoodleError(f"{where(source, int(linenos[i]), f'{name}.ok')}: ok must be 1 or 0, got {okv[i]:g}")
        ok = okv == 1
        p, q = check_poses(ok, values[:, c + 1 : c + 4], values[:, c + 4 : c + 8], source, linenos, name)
        ok, p, q = drop_impossible(rel_t, p * scale, q, ok, source, linenos, name, columns[c + 1 : c + 4])
        p, q = to_ours(p, q, header["convention"])
        tracks.append(Track(name, rel_t, p, q, ok, role=role, serial=serial))
    return Doodle(tuple(tracks), header["rate"], header["device"], source, dict(header["meta"]))


# --------------------------------------------------------------------------- writing


def _file_rows(doodle: Doodle, convention: str, units: str) -> np.ndarray:
    """The data block of ``doodle`` as an ``(n, 1 + 8k)`` float array in the file's frame."""
    if not doodle.tracks:
        raise DoodleError(f"{doodle.source}: a doodle file needs at least one track")
    t = np.asarray(doodle.tracks[0].t, dtype=float)
    for tr in doodle.tracks[1:]:
        if len(tr) != len(t) or not np.allclose(tr.t, t, rtol=0, atol=1e-9):
            raise DoodleError(
                f"{doodle.source}: track {tr.name} does not share the clock of track {doodle.tracks[0].name}; "
                "resample the tracks onto one clock first"
            )
    check_count(len(t), doodle.source)
    if not np.isfinite(t).all() or (np.diff(np.round(t, 6)) <= 0).any():
        raise DoodleError(
            f"{doodle.source}: times must be finite and strictly increasing at microsecond resolution to be written"
        )
    out = np.empty((len(t), 1 + 8 * len(doodle.tracks)))
    out[:, 0] = t
    for j, tr in enumerate(doodle.tracks):
        ok = np.asarray(tr.valid, dtype=bool)
        p, q = np.array(tr.p, dtype=float), np.array(tr.q, dtype=float)
        finite = np.isfinite(p).all(axis=1) & np.isfinite(q).all(axis=1)
        norm = np.linalg.norm(np.where(finite[:, None], q, 1.0), axis=1)
        bad = np.flatnonzero(ok & (~finite | (np.abs(norm - 1.0) > QUAT_NORM_TOL)))
        if bad.size:
            i = int(bad[0])
            raise DoodleError(
                f"{doodle.source}: track {tr.name} sample {i} (t={t[i]:.6f}) is marked valid "
                "but its pose is not finite or its quaternion is not unit"
            )
        p, q = from_ours(p, q, convention)
        c = 1 + 8 * j
        out[:, c] = ok
        out[:, c + 1 : c + 4] = np.where(ok[:, None], p / UNITS[units], np.nan)
        out[:, c + 4 : c + 8] = np.where(ok[:, None], q, np.nan)
    return out


def format_rows(rows: np.ndarray, n_tracks: int, chunk: int = 20000) -> Iterator[str]:
    """Yield the text of the data rows, ``chunk`` rows at a time, each row ending in a newline."""
    fmt = row_format(n_tracks) + "\n"
    for start in range(0, len(rows), chunk):
        yield "".join(fmt % tuple(r) for r in rows[start : start + chunk].tolist())


def write_doodle(path, doodle: Doodle, convention: str = "doodle") -> None:
    """Write ``doodle`` (our frame, metres) to ``path`` as a version 1 doodle file, atomically.

    Positions are written in metres, converted to ``convention``; t (seconds from the
    first sample), positions and quaternions with 6 decimals; invalid samples as
    ``0,nan,…``. ``doodle.meta`` becomes ``x-`` header lines. Raises DoodleError for an
    unknown convention, tracks that do not share one clock, fewer than two samples,
    times that do not strictly increase at microsecond resolution, a valid sample with a
    non-finite pose or non-unit quaternion, or a failed write; an existing file at
    ``path`` is then left untouched.
    """
    tracks = [(tr.name, tr.role, tr.serial) for tr in doodle.tracks]
    header = format_header(tracks, doodle.rate, doodle.device, convention, "m", doodle.meta)
    rows = _file_rows(doodle, convention, "m")

    def chunks() -> Iterator[str]:
        yield header
        yield from format_rows(rows, len(tracks))

    atomic_write(path, chunks())


class DoodleWriter:
    """Append samples to a new doodle file while recording, safe against a crash.

    ``DoodleWriter(path, tracks, rate, device, convention="doodle", units="m")`` writes the
    header at once; ``tracks`` is a list of ``(name, role, serial)`` (or of names).
    ``append(t, poses)`` writes one row: ``t`` in seconds (strictly increasing), ``poses`` one
    ``(p, q, ok)`` per track with ``p`` (3,) in metres and ``q`` (4,) xyzw in OUR frame (the
    writer converts to ``convention`` and ``units``, like :func:`write_doodle`). The file is
    flushed and fsync'ed on the first row, then at most once per second of sample time, and
    on ``close()``: a process killed mid-recording loses at most about one second.

    Refuses to replace an existing file unless ``overwrite=True``. Raises DoodleError for a
    bad header (see :func:`format_header`), a time that does not increase, the wrong number
    of poses, or an ``ok`` pose that is not finite or whose quaternion is not unit (norm
    within 0.1 of 1; it is renormalised).
    """

    def __init__(
        self,
        path,
        tracks,
        rate: float,
        device: str,
        convention: str = "doodle",
        units: str = "m",
        meta: dict | None = None,
        overwrite: bool = False,
    ):
        self.path = Path(path)
        self.tracks = [(tr, "", "") if isinstance(tr, str) else tuple(tr) + ("",) * (3 - len(tr)) for tr in tracks]
        self.convention = convention
        self.scale = 1.0 / UNITS.get(units, 1.0)
        header = format_header(self.tracks, rate, device, convention, units, meta)
        self._fmt = row_format(len(self.tracks)) + "\n"
        self._last_t: float | None = None
        self._last_sync: float | None = None
        self.rows = 0
        try:
            self._fh = open(self.path, "w" if overwrite else "x", encoding="utf-8", newline="\n")
        except FileExistsError:
            raise DoodleError(f"{self.path}: already exists (not overwriting a recording)") from None
        except OSError as exc:
            raise DoodleError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        self._fh.write(header)
        self.sync()

    def append(self, t: float, poses) -> None:
        """Write one sample row; see the class docstring for what ``poses`` holds."""
        if self._fh is None:
            raise DoodleError(f"{self.path}: writer is closed")
        t = float(t)
        if not np.isfinite(t) or (self._last_t is not None and round(t, 6) <= round(self._last_t, 6)):
            raise DoodleError(f"{self.path}: sample time {t} does not come after {self._last_t}")
        if len(poses) != len(self.tracks):
            raise DoodleError(f"{self.path}: got {len(poses)} poses for {len(self.tracks)} tracks")
        values = [t]
        for (name, _, _), (p, q, ok) in zip(self.tracks, poses):
            if ok:
                p = np.asarray(p, dtype=float).reshape(3)
                q = np.asarray(q, dtype=float).reshape(4)
                norm = float(np.linalg.norm(q))
                if not (np.isfinite(p).all() and np.isfinite(q).all()) or abs(norm - 1.0) > QUAT_NORM_TOL:
                    raise DoodleError(
                        f"{self.path}: track {name} at t={t}: pose marked ok is not finite or not a unit quaternion"
                    )
                p, q = from_ours(p, q / norm, self.convention)
                values += [1, *(p * self.scale).tolist(), *q.tolist()]
            else:
                values += [0] + [float("nan")] * 7
        self._fh.write(self._fmt % tuple(values))
        self.rows += 1
        self._last_t = t
        if self._last_sync is None or t - self._last_sync >= SYNC_EVERY_S:
            self.sync()
            self._last_sync = t

    def sync(self) -> None:
        """Flush Python's buffer and fsync the file to disk."""
        if self._fh is not None:
            self._fh.flush()
            os.fsync(self._fh.fileno())

    def close(self) -> None:
        """Sync and close; calling it again does nothing."""
        if self._fh is not None:
            try:
                self.sync()
            finally:
                self._fh.close()
                self._fh = None

    def __enter__(self) -> "DoodleWriter":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
