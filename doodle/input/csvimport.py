"""Import plain CSV pose recordings (e.g. ``data/vive-gestures``) as a Doodle.

Default layout (a header row is required for it): a time column named ``t``, ``time`` or
``timestamp`` (any case), and one track per column prefix: the seven columns
``PREFIX_px, PREFIX_py, PREFIX_pz, PREFIX_qx, PREFIX_qy, PREFIX_qz, PREFIX_qw`` make a track
named ``PREFIX``, tracks in order of first appearance. Other columns are ignored.

A column map overrides the layout: ``{"t": "time", "c0.px": "x", …, "c0.qw": "w"}`` maps our
names (``t`` and ``TRACK.px`` … ``TRACK.qw``) to CSV column names or 0-based indices
(indices are the only choice for a file without a header row).

Values: positions in metres, quaternions xyzw. A NaN in any of a track's seven values on a
row marks that sample invalid (lost tracking) for that track; otherwise the quaternion's
norm must be within 0.1 of 1 (it is renormalised). Times are seconds, strictly increasing;
``Track.t`` is seconds from the first sample. Poses are converted from the file's
coordinate convention to ours. A recording cut off mid-line (a crash while exporting) loads up
to its last whole row, with a warning, as a doodle file does; a malformed line before the
last is an error.
"""

from __future__ import annotations

import csv
import math
import re
import warnings
from pathlib import Path

import numpy as np

from doodle.input.conventions import convention_matrix, to_ours
from doodle.core.errors import DoodleError, where
from doodle.input.fileformat import (MAX_RATE, MIN_RATE, NAME_RE, check_count, check_finite_or_nan, check_poses,
                                     check_times)
from doodle.core.model import Doodle, Track
from doodle.input.repair import drop_impossible

POSE_FIELDS = ("px", "py", "pz", "qx", "qy", "qz", "qw")
TIME_NAMES = ("t", "time", "timestamp")
_KEY_RE = re.compile(r"([A-Za-z0-9_-]+)\.(px|py|pz|qx|qy|qz|qw)")


def parse_column_map(text: str) -> dict[str, str | int]:
    """Parse a column map written ``t=time,c0.px=x,c0.py=y,…`` into a dict.

    A value of digits only becomes an int (a 0-based column index); other values are
    column names. Raises DoodleError for an entry without ``=``, an empty name or value,
    a key that is neither ``t`` nor ``TRACK.px`` … ``TRACK.qw``, or a repeated key.
    """
    mapping: dict[str, str | int] = {}
    for entry in str(text).split(","):
        entry = entry.strip()
        if not entry:
            continue
        key, eq, value = entry.partition("=")
        key, value = key.strip(), value.strip()
        if not eq or not key or not value:
            raise DoodleError(f"column map: {entry!r} is not of the form ours=theirs (e.g. c0.px=x)")
        _check_key(key)
        if key in mapping:
            raise DoodleError(f"column map: {key!r} is given twice")
        mapping[key] = int(value) if value.isdigit() else value
    if not mapping:
        raise DoodleError("column map is empty (expected e.g. t=time,c0.px=x,...)")
    return mapping


def _check_key(key: str) -> None:
    if key != "t" and not _KEY_RE.fullmatch(key):
        raise DoodleError(
            f"column map: unknown name {key!r} (expected t or TRACK.px/py/pz/qx/qy/qz/qw, "
            "TRACK made of letters, digits, _ and -)"
        )


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _tracks_from_map(columns: dict, source: str) -> tuple[object, dict[str, list]]:
    """``(time_spec or None, {track: [7 specs]})`` from a column map, checking completeness."""
    tracks: dict[str, dict] = {}
    for key, spec in columns.items():
        _check_key(key)
        if key != "t":
            name, field = key.split(".")
            tracks.setdefault(name, {})[field] = spec
    if not tracks:
        raise DoodleError(f"{source}: column map names no track columns (e.g. c0.px=x)")
    out = {}
    for name, fields in tracks.items():
        missing = [f"{name}.{f}" for f in POSE_FIELDS if f not in fields]
        if missing:
            raise DoodleError(f"{source}: column map lacks {', '.join(missing)}")
        out[name] = [fields[f] for f in POSE_FIELDS]
    return columns.get("t"), out


def _tracks_from_header(header: list[str], source: str) -> tuple[object, dict[str, list]]:
    """``(time column name or None, {track: [7 column names]})`` from the default layout."""
    lower = [h.lower() for h in header]
    time = next((header[lower.index(n)] for n in TIME_NAMES if n in lower), None)
    prefixes: list[str] = []
    for h in header:
        m = re.fullmatch(r"(.+)_(px|py|pz|qx|qy|qz|qw)", h)
        if m and m.group(1) not in prefixes:
            prefixes.append(m.group(1))
    if not prefixes:
        raise DoodleError(
            f"{source}: no track columns found (expected PREFIX_px … PREFIX_qw, or give a column map)"
        )
    out = {}
    for prefix in prefixes:
        for f in POSE_FIELDS:
            if f"{prefix}_{f}" not in header:
                raise DoodleError(f"{source}: track {prefix} lacks the column {prefix}_{f}")
        if not NAME_RE.fullmatch(prefix):
            raise DoodleError(
                f"{source}: track name {prefix!r} (from its columns) must match [A-Za-z0-9_-]+; give a column map"
            )
        out[prefix] = [f"{prefix}_{f}" for f in POSE_FIELDS]
    return time, out


def _index(spec, header: list[str] | None, width: int, source: str, ours: str) -> int:
    """The 0-based index of a column given by name or index."""
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        if not 0 <= spec < width:
            raise DoodleError(f"{source}: column index {spec} for {ours} is out of range (the file has {width} columns)")
        return int(spec)
    if header is None:
        raise DoodleError(f"{source}: the file has no header row, so {ours} needs a 0-based column index, not {spec!r}")
    if spec not in header:
        raise DoodleError(f"{source}: no column {spec!r} (for {ours}); columns: {', '.join(header)}")
    return header.index(spec)


def _row_parses(line: str, width: int, used: list[int]) -> bool:
    """Whether a data line has ``width`` fields and numbers in the ``used`` ones."""
    fields = line.split(",")
    return len(fields) == width and all(_is_number(fields[j]) for j in used)


def _parse_data(rows: list[str], linenos: list[int], width: int, used: list[int], names: list[str], source: str):
    """Parse the used columns of the data lines into a float array ``(n, len(used))``: by
    ``np.loadtxt`` when every line has ``width`` fields and it reads them (it reads a
    subset of what ``float`` does, to the same values); else line by line, which finds the
    line and column at fault (or reads what only ``float`` reads, ``1_000``, as before)."""
    if rows and len(set(used)) == len(used) and not any(line.count(",") != width - 1 for line in rows):
        try:
            return np.loadtxt(rows, delimiter=",", usecols=used, comments=None, dtype=np.float64, ndmin=2,
                              encoding=None)
        except ValueError:
            pass
    fields = [line.split(",") for line in rows]
    for fs, lineno in zip(fields, linenos):
        if len(fs) != width:
            raise DoodleError(f"{where(source, lineno)}: {len(fs)} fields, expected {width}")
    flat = [fs[j] for fs in fields for j in used]
    try:
        return np.array(flat, dtype=np.float64).reshape(len(rows), len(used))
    except ValueError:
        for fs, lineno in zip(fields, linenos):
            for j, name in zip(used, names):
                if not _is_number(fs[j]):
                    raise DoodleError(f"{where(source, lineno, name)}: {fs[j].strip()!r} is not a number") from None
        raise DoodleError(f"{source}: cannot parse the data rows") from None


def read_csv(
    path,
    convention: str = "unity",
    columns: dict | None = None,
    rate: float | None = None,
    device: str = "vive-controller",
) -> Doodle:
    """Load a plain CSV of timestamped poses as a Doodle in our frame.

    ``convention`` names the file's coordinate convention (see :mod:`doodle.input.conventions`).
    ``columns`` is an optional column map (see the module docstring and
    :func:`parse_column_map`). ``rate`` is the nominal rate in Hz: without a time column,
    samples are taken to be ``1/rate`` apart; when not given it is estimated as
    ``1/median(dt)`` rounded to 0.1 Hz. Blank lines are skipped. The first non-empty line is
    a header row if any of its fields is not a number.

    A NaN in any of a track's 7 values on a row marks that sample invalid (lost tracking), and
    so does a physically impossible position (:func:`doodle.input.repair.drop_impossible`,
    with a warning). A last line without a newline that does not parse is dropped with a
    warning (``warnings.warn``). Raises DoodleError (naming the file, and the line and column
    where there is one) for:
    no header and no column map, a missing column, no time column and no rate, a row with
    the wrong number of fields, a value that is not a number or is infinite, a zero or
    non-unit quaternion, times that are not finite or do not strictly increase, fewer
    than two samples, an unknown convention.
    """
    path = Path(path)
    source = str(path)
    convention_matrix(convention)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DoodleError(f"{source}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise DoodleError(f"{source}: cannot read: {exc.strerror or exc}") from None
    numbered = [(i + 1, line) for i, line in enumerate(text.split("\n")) if line.strip()]
    if not numbered:
        raise DoodleError(f"{source}: no samples (empty file)")
    first = next(csv.reader([numbered[0][1]]))
    has_header = not all(_is_number(f) for f in first)
    header = [h.strip() for h in first] if has_header else None
    width = len(first)
    if has_header:
        numbered = numbered[1:]
    if columns is None:
        if header is None:
            raise DoodleError(f"{source}: no header row; give a column map (e.g. t=0,c0.px=1,…,c0.qw=7)")
        time_spec, track_specs = _tracks_from_header(header, source)
    else:
        time_spec, track_specs = _tracks_from_map(columns, source)
    if time_spec is None and rate is None:
        raise DoodleError(f"{source}: no time column (t, time or timestamp); give one in the column map or give a rate")

    used, names = [], []
    if time_spec is not None:
        used.append(_index(time_spec, header, width, source, "t"))
        names.append(header[used[-1]] if header else "t")
    for track, specs in track_specs.items():
        for f, spec in zip(POSE_FIELDS, specs):
            used.append(_index(spec, header, width, source, f"{track}.{f}"))
            names.append(header[used[-1]] if header else f"{track}.{f}")

    cut = not text.endswith("\n") and numbered and numbered[-1][0] == text.count("\n") + 1
    if cut and not _row_parses(numbered[-1][1], width, used):
        lineno = numbered[-1][0]
        numbered = numbered[:-1]
        warnings.warn(f"{source}:{lineno}: last row is incomplete (cut off?); loaded {len(numbered)} whole rows",
                      stacklevel=2)
    linenos = np.array([n for n, _ in numbered], dtype=np.int64)
    values = _parse_data([line for _, line in numbered], list(linenos), width, used, names, source)
    check_count(len(values), source)
    check_finite_or_nan(values, names, source, linenos)
    if time_spec is not None:
        t = values[:, 0]
        check_times(t, source, linenos, names[0])
        values = values[:, 1:]
    else:
        t = np.arange(len(values)) / float(rate)
    if rate is None:
        step = float(np.median(np.diff(t)))
        rate = round(1.0 / step, 1) if step > 1.0 / MAX_RATE / 10 else math.inf
        if not MIN_RATE <= rate <= MAX_RATE:
            raise DoodleError(f"{source}: samples {step:.3g} apart on median make a rate of {rate:g} Hz, outside "
                              f"{MIN_RATE:g}–{MAX_RATE:g} Hz: are the times in seconds?")
    rate = float(rate)
    if not MIN_RATE <= rate <= MAX_RATE:
        raise DoodleError(f"{source}: rate must be a number from {MIN_RATE:g} to {MAX_RATE:g} Hz, got {rate}")

    rel_t = t - t[0]
    base = 1 if time_spec is not None else 0  # the time column leads ``names``
    tracks = []
    for j, track in enumerate(track_specs):
        block = values[:, 7 * j : 7 * j + 7]
        ok = ~np.isnan(block).any(axis=1)
        cols = names[base + 7 * j : base + 7 * j + 7]
        p, q = check_poses(ok, block[:, :3], block[:, 3:], source, linenos, track, cols)
        ok, p, q = drop_impossible(rel_t, p, q, ok, source, linenos, track, cols[:3])
        p, q = to_ours(p, q, convention)
        tracks.append(Track(track, rel_t, p, q, ok))
    return Doodle(tuple(tracks), rate, device, source, {})
