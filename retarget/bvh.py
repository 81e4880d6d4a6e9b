"""BVH (Biovision Hierarchy) reading and writing.

Reading (:func:`read_bvh`, :func:`read_bvh_with_unit`):

- HIERARCHY: one ``ROOT``, nested ``JOINT`` blocks and ``End Site`` blocks. Each joint has one
  ``OFFSET x y z`` and one ``CHANNELS n name…`` with n = 3 or 6: 0 or 3 position channels
  (``Xposition Yposition Zposition``) and 0 or 3 rotation channels (``Xrotation Yrotation
  Zrotation``), in ANY order, which may differ from joint to joint. Channel names are
  matched case-insensitively and stored in canonical spelling, in file order, in
  :attr:`Skeleton.channels`. A joint name is the rest of its ``ROOT``/``JOINT`` line (so
  names with spaces survive). Joints are numbered in file order, so parents come first.
- MOTION: ``Frames: N`` (a positive integer), ``Frame Time: t`` (seconds, from 1e-6 to 1000,
  kept exactly as ``float(t)`` — the rate is never rounded), then N lines of one value per
  channel, joints in file order. Blank lines are skipped; lines after the N-th frame are
  ignored (as other readers do).
- Rotations: a joint's rotation channels, in the order listed, compose as INTRINSIC
  rotations: ``Zrotation Xrotation Yrotation`` with values a, b, c gives
  R = Rz(a)·Rx(b)·Ry(c), i.e. ``Rotation.from_euler("ZXY", [a, b, c], degrees=True)``.
  Stored as quaternions (x, y, z, w) in :attr:`Motion.rotations`.
- Translations: a joint's position channels REPLACE its OFFSET (the BVH convention, as in
  bvhio and Blender): :attr:`Motion.translations` ``[f, j]`` is the (x, y, z) of the joint's
  position channels at frame f, whatever their order in the file, or its OFFSET when it has
  no position channels (the root too). The OFFSET is kept in :attr:`Skeleton.offsets`.

  In the Bandai Namco files every joint has 6 channels. Measured over all 192 files: the
  position values of the joints below ``Hips`` equal their OFFSET up to the file's
  rounding (at most 1e-5 cm), so they carry no motion; ``Hips`` (child of ``joint_Root``)
  carries the body's translation (up to 11 m from its OFFSET), and ``joint_Root`` moves
  too (up to 2.7 m) but never rotates. Replacing the OFFSET is what makes these files
  move correctly; adding the channels to the OFFSET would double every bone.
- Units: ``unit`` is metres per file unit; every length (OFFSETs, position channels, End
  Sites) is multiplied by it. ``unit=None`` guesses it with :func:`guess_unit`: 0.01
  (centimetres) when the skeleton's rest height — max minus min of the joints' y in the
  rest pose (forward kinematics of the OFFSETs alone, no rotation) — is more than 10 file
  units, else 1.0 (metres). A human is 1–2 m tall, i.e. 100–200 in centimetres.
- Errors: malformed input raises :class:`DoodleError` whose message starts ``path:line:``;
  so does a length (OFFSET, End Site, position channel) beyond ±1e7 file units — 100 km in
  centimetres: a corrupt file, whose sums of offsets would overflow.

Writing (:func:`write_bvh`) keeps each joint's channel layout as stored in the skeleton
(joints built without one get ``Xposition Yposition Zposition Zrotation Xrotation
Yrotation`` on the root, ``Zrotation Xrotation Yrotation`` elsewhere, plus position
channels where their translation moves), so read → write → read keeps the layout. Angles
come from the quaternions with the joint's own (intrinsic) channel order; values are
written in fixed point with ``precision`` decimals, ``Frame Time`` with ``repr`` (exact
round trip). The file is written atomically.

Speed: the MOTION block is parsed by numpy's C text reader (``np.loadtxt``) in one call —
the same correctly rounded values as ``float()`` on each field, and as pandas' C CSV reader
(which this module used before: identical on all 240 BVH files of the built-in library and
``../shared/data``; a 5 MB clip reads ~10 % slower than with pandas, a short clip ~30 %
faster, and pandas' import, a quarter to a third of a second at start-up, is gone) — and
formatted with vectorised numpy code (digits from a lookup table, no Python per value);
Euler angles ↔ quaternions are computed in numpy (:mod:`doodle.core.quat`, scipy's results
without importing scipy.spatial), one call per rotation order. Against
bvhio (``bench/bvh_speed.py``): reading is several times faster than its bare
``readAsBvh`` and 20–60× faster than ``readAsHierarchy``; writing is ~8–20× faster than
its ``writeBvh``.
"""

from __future__ import annotations

import math
import numbers
import re
import warnings
from pathlib import Path

import numpy as np
from doodle.core import quat
from doodle.core.errors import DoodleError, where
from retarget.skeleton import POSITION_CHANNELS, ROTATION_CHANNELS, Motion, Skeleton

__all__ = ["read_bvh", "read_bvh_with_unit", "guess_unit", "write_bvh", "format_bvh"]

_CHANNELS = {name.lower(): name for name in POSITION_CHANNELS + ROTATION_CHANNELS}
_FRAMES_RE = re.compile(r"^\s*Frames\s*:\s*(\S*)\s*$")
_FRAME_TIME_RE = re.compile(r"^\s*Frame\s+Time\s*:\s*(\S*)\s*$")
_DEFAULT_ROOT_CHANNELS = POSITION_CHANNELS + ("Zrotation", "Xrotation", "Yrotation")
_DEFAULT_CHANNELS = ("Zrotation", "Xrotation", "Yrotation")
UNIT_GUESS_HEIGHT = 10.0  # file units: a rest height above this means centimetres
MAX_LENGTH = 1e7  # file units an OFFSET or position may reach: 100 km in centimetres; sums stay finite
MIN_FRAME_TIME, MAX_FRAME_TIME = 1e-6, 1e3  # seconds per frame: rates from 1 MHz down to one frame in 17 minutes


# --------------------------------------------------------------------------- reading


def read_bvh(path, unit: float | None = None) -> Motion:
    """Read a BVH file into a :class:`Motion` in metres (see the module docstring).

    ``unit`` is metres per file unit; ``None`` guesses it (:func:`guess_unit`).
    """
    return read_bvh_with_unit(path, unit)[0]


def read_bvh_with_unit(path, unit: float | None = None) -> tuple[Motion, float]:
    """Like :func:`read_bvh`, and also return the unit used (metres per file unit)."""
    source = str(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise DoodleError(f"{source}: cannot read: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return _parse(text.lstrip("\ufeff"), source, unit)


def guess_unit(skeleton: Skeleton) -> float:
    """Metres per file unit for a skeleton still in file units: 0.01 when its rest height
    (max minus min of the joints' y, forward kinematics of the offsets without rotation)
    is more than 10 file units, else 1.0."""
    rest = _rest_positions(skeleton.parents, skeleton.offsets)
    height = float(np.ptp(rest[:, 1])) if len(rest) else 0.0
    return 0.01 if height > UNIT_GUESS_HEIGHT else 1.0


def _rest_positions(parents: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    rest = np.zeros((len(parents), 3))
    for j, p in enumerate(parents):
        rest[j] = offsets[j] + (rest[p] if p >= 0 else 0.0)
    return rest


class _Joint:
    __slots__ = ("name", "parent", "line", "offset", "channels", "end_site")

    def __init__(self, name: str, parent: int, line: int) -> None:
        self.name, self.parent, self.line = name, parent, line
        self.offset: np.ndarray | None = None
        self.channels: tuple[str, ...] | None = None
        self.end_site: np.ndarray | None = None


def _is_positive(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value) and value > 0


def _parse(text: str, source: str, unit: float | None) -> tuple[Motion, float]:
    if unit is not None and not _is_positive(unit):
        raise DoodleError(f"{source}: unit must be a positive number of metres per file unit, not {unit!r}")
    lines = text.splitlines()
    if not any(line.strip() for line in lines):
        raise DoodleError(f"{where(source, 1)}: empty file (expected HIERARCHY)")
    motion_at = next((k for k, line in enumerate(lines) if line.lstrip().startswith("MOTION")
                      and line.split()[0] == "MOTION"), None)
    joints = _parse_hierarchy(lines if motion_at is None else lines[:motion_at], source,
                              motion_line=None if motion_at is None else motion_at + 1)
    if motion_at is None:
        raise DoodleError(f"{where(source, len(lines))}: missing MOTION section after the HIERARCHY")
    if len(lines[motion_at].split()) != 1:
        raise DoodleError(f"{where(source, motion_at + 1)}: unexpected text after MOTION: "
                          f"{lines[motion_at].split()[1]!r}")
    frames, frame_time, data_at = _parse_motion_header(lines, motion_at + 1, source)
    width = sum(len(j.channels) for j in joints)
    data = _parse_motion_data(lines, data_at, frames, width, source)
    _check_positions(data, [c for j in joints for c in j.channels], lines, data_at, source)

    names = tuple(j.name for j in joints)
    parents = np.array([j.parent for j in joints], dtype=np.int64)
    offsets = np.array([j.offset for j in joints], dtype=float).reshape(-1, 3)
    if unit is None:
        probe = Skeleton(names, parents, offsets, tuple(j.channels for j in joints))
        unit = guess_unit(probe)
    unit = float(unit)

    n_joints = len(joints)
    translations = np.empty((frames, n_joints, 3))
    rotations = np.empty((frames, n_joints, 4))
    rotations[:] = (0.0, 0.0, 0.0, 1.0)
    by_order: dict[str, tuple[list[int], list[int]]] = {}  # order -> (joints, their angle columns)
    col = 0
    for k, joint in enumerate(joints):
        chans = joint.channels
        pos_cols = {c[0]: col + i for i, c in enumerate(chans) if c in POSITION_CHANNELS}
        if pos_cols:
            translations[:, k] = data[:, [pos_cols["X"], pos_cols["Y"], pos_cols["Z"]]]
        else:
            translations[:, k] = joint.offset
        order = "".join(c[0] for c in chans if c in ROTATION_CHANNELS)
        if order:
            ks, cols = by_order.setdefault(order, ([], []))
            ks.append(k)
            cols += [col + i for i, c in enumerate(chans) if c in ROTATION_CHANNELS]
        col += len(chans)
    for order, (ks, cols) in by_order.items():  # all joints with one order in one go
        angles = data[:, cols].reshape(-1, 3)
        rotations[:, ks] = quat.from_euler(order, angles, degrees=True).reshape(frames, len(ks), 4)
    translations *= unit
    end_sites = {k: j.end_site * unit for k, j in enumerate(joints) if j.end_site is not None}
    skeleton = Skeleton(names, parents, offsets * unit, tuple(j.channels for j in joints), end_sites)
    return Motion(skeleton, translations, rotations, frame_time), unit


def _parse_hierarchy(lines: list[str], source: str, motion_line: int | None) -> list[_Joint]:
    """Joints of the HIERARCHY in ``lines`` (the file up to its MOTION line, if any)."""
    toks: list[str] = []
    line_of: list[int] = []
    for k, line in enumerate(lines):
        parts = line.split()
        toks += parts
        line_of += [k + 1] * len(parts)
    n = len(toks)
    last_line = max(len(lines), 1)

    def fail(i: int, message: str):
        raise DoodleError(f"{where(source, line_of[i] if i < n else last_line)}: {message}")

    def rest_of_line(i: int) -> int:
        """Index just past the last token on token i's line."""
        k = i
        while k < n and line_of[k] == line_of[i]:
            k += 1
        return k

    def expect(i: int, token: str, context: str) -> int:
        if i >= n:
            fail(i, f"file ends where {token!r} was expected {context}")
        if toks[i] != token:
            fail(i, f"expected {token!r} {context}, found {toks[i]!r}")
        return i + 1

    def read_offset(i: int, what: str) -> tuple[np.ndarray, int]:
        end = rest_of_line(i)
        values = toks[i + 1:end]
        if len(values) != 3:
            fail(i, f"bad OFFSET of {what}: expected 3 numbers, found {len(values)}")
        try:
            offset = np.array([float(v) for v in values])
        except ValueError:
            fail(i, f"bad OFFSET of {what}: {' '.join(values)!r} is not 3 numbers")
        if not np.all(np.isfinite(offset)) or np.abs(offset).max() > MAX_LENGTH:
            fail(i, f"bad OFFSET of {what}: values must be finite, within ±{MAX_LENGTH:g} file units")
        return offset, end

    if n == 0:
        fail(0, "missing HIERARCHY before MOTION")
    if toks[0] != "HIERARCHY":
        fail(0, f"expected HIERARCHY at the start of a BVH file, found {toks[0]!r}")
    i = 1
    if i >= n:
        fail(i, "missing ROOT after HIERARCHY")
    if toks[i] != "ROOT":
        fail(i, f"expected ROOT after HIERARCHY, found {toks[i]!r}")
    joints: list[_Joint] = []
    stack: list[int] = []
    while True:
        if i >= n:
            if not stack:
                fail(i, "missing MOTION section after the HIERARCHY")
            open_joint = joints[stack[-1]]
            if motion_line is not None:
                raise DoodleError(f"{where(source, motion_line)}: MOTION reached while joint {open_joint.name!r} "
                                  f"(line {open_joint.line}) is still open: unbalanced braces, missing '}}'")
            fail(i, f"file ends inside joint {open_joint.name!r} (line {open_joint.line}): "
                    f"unbalanced braces, missing '}}'")
        tok = toks[i]
        if tok in ("ROOT", "JOINT"):
            if tok == "ROOT" and joints:
                fail(i, "only one ROOT is supported" if not stack else "ROOT inside a joint")
            if tok == "JOINT" and not stack:
                fail(i, "JOINT outside of any joint (unbalanced braces?)")
            end = rest_of_line(i)
            name_toks = toks[i + 1:end]
            if name_toks and name_toks[-1] == "{":
                name_toks = name_toks[:-1]
                end -= 1
            if not name_toks:
                fail(i, f"{tok} without a joint name")
            if "{" in name_toks or "}" in name_toks:
                fail(i, f"unexpected brace in the name of a {tok}")
            name = " ".join(name_toks)
            if any(j.name == name for j in joints):
                fail(i, f"duplicate joint name {name!r}")
            joints.append(_Joint(name, stack[-1] if stack else -1, line_of[i]))
            i = expect(end, "{", f"after {tok} {name}")
            stack.append(len(joints) - 1)
        elif tok == "OFFSET":
            if not stack:
                fail(i, "OFFSET outside of any joint")
            joint = joints[stack[-1]]
            if joint.offset is not None:
                fail(i, f"joint {joint.name!r} has more than one OFFSET")
            joint.offset, i = read_offset(i, f"joint {joint.name!r}")
        elif tok == "CHANNELS":
            if not stack:
                fail(i, "CHANNELS outside of any joint")
            joint = joints[stack[-1]]
            if joint.channels is not None:
                fail(i, f"joint {joint.name!r} has more than one CHANNELS line")
            end = rest_of_line(i)
            if i + 1 >= end:
                fail(i, f"CHANNELS of joint {joint.name!r} without a count")
            try:
                count = int(toks[i + 1])
            except ValueError:
                fail(i, f"CHANNELS count {toks[i + 1]!r} of joint {joint.name!r} is not a whole number")
            names = toks[i + 2:end]
            if count not in (3, 6):
                fail(i, f"CHANNELS count {count} of joint {joint.name!r} is not supported (must be 3 or 6)")
            if len(names) != count:
                fail(i, f"CHANNELS of joint {joint.name!r} says {count} but names {len(names)}")
            canonical = []
            for c in names:
                if c.lower() not in _CHANNELS:
                    fail(i, f"unknown channel name {c!r} in joint {joint.name!r} "
                            f"(expected X/Y/Z position or rotation)")
                canonical.append(_CHANNELS[c.lower()])
            if len(set(canonical)) != len(canonical):
                fail(i, f"repeated channel in joint {joint.name!r}")
            n_pos = sum(c in POSITION_CHANNELS for c in canonical)
            if n_pos not in (0, 3) or len(canonical) - n_pos not in (0, 3):
                fail(i, f"CHANNELS of joint {joint.name!r} must be 3 position and/or 3 rotation channels")
            joint.channels = tuple(canonical)
            i = end
        elif tok == "End":
            if not stack:
                fail(i, "End Site outside of any joint")
            joint = joints[stack[-1]]
            if i + 1 >= n or toks[i + 1] != "Site" or line_of[i + 1] != line_of[i]:
                fail(i, "expected 'End Site'")
            if joint.end_site is not None:
                fail(i, f"joint {joint.name!r} has more than one End Site")
            i = expect(i + 2, "{", "after End Site")
            i = expect(i, "OFFSET", "in End Site")
            joint.end_site, i = read_offset(i - 1, f"the End Site of {joint.name!r}")
            i = expect(i, "}", "to close the End Site")
        elif tok == "}":
            if not stack:
                fail(i, "unbalanced braces: unexpected '}'")
            joint = joints[stack.pop()]
            if joint.offset is None:
                fail(i, f"joint {joint.name!r} (line {joint.line}) has no OFFSET")
            if joint.channels is None:
                fail(i, f"joint {joint.name!r} (line {joint.line}) has no CHANNELS")
            i += 1
            if not stack:
                break
        elif tok == "{":
            fail(i, "unexpected '{'")
        else:
            fail(i, f"unexpected token {tok!r}" + (f" in joint {joints[stack[-1]].name!r}" if stack else ""))
    if i < n:
        if toks[i] == "ROOT":
            fail(i, "only one ROOT is supported")
        if toks[i] == "}":
            fail(i, "unbalanced braces: unexpected '}'")
        fail(i, f"unexpected token {toks[i]!r} after the HIERARCHY (expected MOTION)")
    return joints


def _next_nonblank(lines: list[str], k: int) -> int:
    while k < len(lines) and not lines[k].strip():
        k += 1
    return k


def _parse_motion_header(lines: list[str], k: int, source: str) -> tuple[int, float, int]:
    k = _next_nonblank(lines, k)
    if k >= len(lines):
        raise DoodleError(f"{where(source, len(lines))}: missing 'Frames:' after MOTION")
    m = _FRAMES_RE.match(lines[k])
    if not m:
        raise DoodleError(f"{where(source, k + 1)}: expected 'Frames: N' after MOTION, found {lines[k].strip()!r}")
    try:
        frames = int(m.group(1))
    except ValueError:
        frames = 0
    if frames <= 0:
        raise DoodleError(f"{where(source, k + 1)}: Frames must be a positive whole number, not {m.group(1)!r}")
    k = _next_nonblank(lines, k + 1)
    if k >= len(lines):
        raise DoodleError(f"{where(source, len(lines))}: missing 'Frame Time:' after Frames")
    m = _FRAME_TIME_RE.match(lines[k])
    if not m:
        raise DoodleError(f"{where(source, k + 1)}: expected 'Frame Time: seconds' after Frames, "
                          f"found {lines[k].strip()!r}")
    try:
        frame_time = float(m.group(1))
    except ValueError:
        frame_time = float("nan")
    if not (math.isfinite(frame_time) and MIN_FRAME_TIME <= frame_time <= MAX_FRAME_TIME):
        raise DoodleError(f"{where(source, k + 1)}: Frame Time must be a positive number of seconds, from "
                          f"{MIN_FRAME_TIME:g} to {MAX_FRAME_TIME:g}, not {m.group(1)!r}")
    return frames, frame_time, k + 1


def _parse_motion_data(lines: list[str], start: int, frames: int, width: int, source: str) -> np.ndarray:
    body = lines[start:start + frames]
    if len(body) == frames:
        try:  # one C call; a line of the wrong length or a non-number: the careful path says which
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                data = np.loadtxt(body, dtype=float, comments=None, ndmin=2)
        except ValueError:
            data = None
        if data is not None and data.shape == (frames, width) and np.isfinite(data).all():
            return data
    return _diagnose_motion_data(lines, start, frames, width, source)


def _diagnose_motion_data(lines: list[str], start: int, frames: int, width: int, source: str) -> np.ndarray:
    """The careful path: find the first bad motion line and say what is wrong with it."""
    last = len(lines)
    while last > start and not lines[last - 1].strip():
        last -= 1
    rows = []
    k = start
    while len(rows) < frames and k < last:
        parts = lines[k].split()
        if parts:
            frame = len(rows) + 1
            if len(parts) != width:
                if k == last - 1 and len(parts) < width:
                    raise DoodleError(f"{where(source, k + 1)}: file is truncated: the last line (frame {frame} "
                                      f"of {frames}) has {len(parts)} values, expected {width}")
                raise DoodleError(f"{where(source, k + 1)}: motion line (frame {frame}) has {len(parts)} values, "
                                  f"expected {width} (one per channel)")
            try:
                row = [float(v) for v in parts]
            except ValueError:
                bad = next(v for v in parts if not _is_float(v))
                raise DoodleError(f"{where(source, k + 1)}: non-numeric value {bad!r} on motion line "
                                  f"(frame {frame})") from None
            if not all(math.isfinite(v) for v in row):
                bad = next(p for p, v in zip(parts, row) if not math.isfinite(v))
                raise DoodleError(f"{where(source, k + 1)}: value {bad!r} on motion line (frame {frame}) "
                                  f"is not finite")
            rows.append(row)
        k += 1
    if len(rows) < frames:
        raise DoodleError(f"{where(source, max(last, 1))}: file is truncated: it ends after {len(rows)} of "
                          f"{frames} frames (Frames: {frames})")
    return np.array(rows, dtype=float).reshape(frames, width)


def _check_positions(data: np.ndarray, channels: list[str], lines: list[str], start: int, source: str) -> None:
    """Position channels within ±:data:`MAX_LENGTH` file units; else an error naming the line."""
    cols = [k for k, c in enumerate(channels) if c in POSITION_CHANNELS]
    bad = np.argwhere(np.abs(data[:, cols]) > MAX_LENGTH)
    if len(bad):
        frame, col = int(bad[0][0]), cols[int(bad[0][1])]
        k = start
        for _ in range(frame + 1):  # the frame's line: blank lines do not count
            k = _next_nonblank(lines, k) + 1
        raise DoodleError(f"{where(source, k)}: {channels[col]} {data[frame, col]:g} on motion line (frame "
                          f"{frame + 1}) is beyond ±{MAX_LENGTH:g} file units")


def _is_float(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False


# --------------------------------------------------------------------------- writing


def write_bvh(path, motion: Motion, unit: float = 1.0, precision: int = 6) -> None:
    """Write ``motion`` to ``path`` as BVH, atomically (temp file + ``os.replace``).

    Lengths are divided by ``unit`` (metres per file unit: 0.01 writes centimetres);
    channel values and angles (degrees) get ``precision`` decimals; ``Frame Time`` is
    written with ``repr`` so it reads back as exactly ``motion.frame_time``. Each joint
    keeps its channel layout from the skeleton. Raises DoodleError when the motion cannot
    be written faithfully (non-finite values, no frames, a joint without position
    channels whose translation differs from its offset, bad names or channels).
    """
    from doodle.core.files import atomic_write  # local import: keeps reading light

    atomic_write(path, bvh_chunks(motion, unit=unit, precision=precision, source=str(path)))


def format_bvh(motion: Motion, unit: float = 1.0, precision: int = 6, source: str = "BVH") -> str:
    """The text of the BVH file :func:`write_bvh` writes."""
    return "".join(bvh_chunks(motion, unit, precision, source))


ROWS_AT_ONCE = 8192  # frames converted and formatted at once: the text is written block by block


def bvh_chunks(motion: Motion, unit: float = 1.0, precision: int = 6, source: str = "BVH"):
    """The text of the BVH file :func:`write_bvh` writes, in pieces: the hierarchy, then the
    motion's rows :data:`ROWS_AT_ONCE` frames at a time (each converted when it is reached,
    so a long motion never has all its text, angles or rows in memory at once). Everything
    that can make the motion unwritable is checked before the first piece is returned."""
    if not _is_positive(unit):
        raise DoodleError(f"{source}: unit must be a positive number of metres per file unit, not {unit!r}")
    if not isinstance(precision, (int, np.integer)) or not 0 <= precision <= 12:
        raise DoodleError(f"{source}: precision must be a whole number of decimals from 0 to 12")
    precision = int(precision)
    sk = motion.skeleton
    n_frames, n_joints = motion.frames, len(sk)
    if n_frames == 0:
        raise DoodleError(f"{source}: cannot write a motion without frames")
    if n_joints == 0:
        raise DoodleError(f"{source}: cannot write a skeleton without joints")
    frame_time = float(motion.frame_time)
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise DoodleError(f"{source}: frame time must be a positive number of seconds, not {frame_time!r}")
    translations = np.asarray(motion.translations, dtype=float)  # divided by ``unit`` where used
    rotations = np.asarray(motion.rotations, dtype=float)
    offsets = np.asarray(sk.offsets, dtype=float) / unit
    for what, arr in (("translations", translations / unit if unit != 1.0 else translations),
                      ("rotations", rotations), ("offsets", offsets)):
        if not np.isfinite(arr).all():
            f = np.argwhere(~np.isfinite(arr))[0]
            raise DoodleError(f"{source}: cannot write non-finite {what} (at index {tuple(int(v) for v in f)})")
    tol = 10.0 ** -precision

    layouts = []
    for j in range(n_joints):
        name = sk.names[j]
        if not name or " ".join(name.split()) != name or {"{", "}"} & set(name.split()):
            raise DoodleError(f"{source}: joint name {name!r} cannot be written to BVH")
        chans = tuple(sk.channels[j])
        moves = bool(np.abs(translations[:, j] / unit - offsets[j]).max() > tol)
        if not chans:
            chans = _DEFAULT_ROOT_CHANNELS if j == 0 or moves else _DEFAULT_CHANNELS
        bad = [c for c in chans if c not in _CHANNELS.values()]
        n_pos = sum(c in POSITION_CHANNELS for c in chans)
        if bad or len(set(chans)) != len(chans) or n_pos not in (0, 3) or len(chans) - n_pos not in (0, 3):
            raise DoodleError(f"{source}: joint {name!r} has an invalid channel layout {chans!r}")
        if n_pos == 0 and moves:
            raise DoodleError(f"{source}: joint {name!r} has no position channels but its translation differs "
                              f"from its OFFSET; give it position channels")
        if len(chans) == n_pos:
            angle = quat.magnitude(rotations[:, j])
            if float(angle.max(initial=0.0)) > math.radians(tol):
                raise DoodleError(f"{source}: joint {name!r} has no rotation channels but rotates")
        layouts.append(chans)

    orders = ["".join(c[0] for c in chans if c in ROTATION_CHANNELS) for chans in layouts]
    children: list[list[int]] = [[] for _ in range(n_joints)]
    for j in range(1, n_joints):
        children[int(sk.parents[j])].append(j)
    preorder, todo = [], [0]  # the file's joint order (the skeleton's need not be depth first)
    while todo:
        j = todo.pop()
        preorder.append(j)
        todo += reversed(children[j])

    out = ["HIERARCHY\n"]
    end_sites = {int(k): np.asarray(v, dtype=float).reshape(3) / unit for k, v in sk.end_sites.items()}
    if not all(np.isfinite(v).all() for v in end_sites.values()):
        raise DoodleError(f"{source}: cannot write non-finite End Site offsets")

    stack = [(0, 0, False)]  # iterative pre-order emission (deep skeletons cannot overflow)
    while stack:
        j, depth, closing = stack.pop()
        pad = "  " * depth
        if closing:
            if j in end_sites:
                out.append(f"{pad}  End Site\n{pad}  {{\n{pad}    OFFSET {_offset_text(end_sites[j], precision)}\n"
                           f"{pad}  }}\n")
            out.append(f"{pad}}}\n")
            continue
        out.append(f"{pad}{'ROOT' if j == 0 else 'JOINT'} {sk.names[j]}\n{pad}{{\n")
        out.append(f"{pad}  OFFSET {_offset_text(offsets[j], precision)}\n")
        out.append(f"{pad}  CHANNELS {len(layouts[j])} {' '.join(layouts[j])}\n")
        stack.append((j, depth, True))
        for c in reversed(children[j]):
            stack.append((c, depth + 1, False))
    out.append(f"MOTION\nFrames: {n_frames}\nFrame Time: {frame_time!r}\n")
    head = "".join(out)

    def pieces():
        yield head
        for a in range(0, n_frames, ROWS_AT_ONCE):
            block = slice(a, min(a + ROWS_AT_ONCE, n_frames))
            yield _format_rows(_channel_rows(translations[block] / unit, rotations[block], layouts, orders, preorder),
                               precision)

    return pieces()


def _channel_rows(translations: np.ndarray, rotations: np.ndarray, layouts: list, orders: list,
                  preorder: list) -> np.ndarray:
    """(frames, channels) the values of every joint's channels, in the file's joint order:
    positions in file units, Euler angles in degrees."""
    n_frames = len(translations)
    angles: dict[int, np.ndarray] = {}
    for order in set(orders) - {""}:  # one call per distinct order, all its joints at once
        js = [j for j, o in enumerate(orders) if o == order]
        e = quat.as_euler(rotations[:, js].reshape(-1, 4), order, degrees=True)
        e = e.reshape(n_frames, len(js), 3)
        angles.update((j, e[:, n]) for n, j in enumerate(js))
    data = np.empty((n_frames, sum(len(c) for c in layouts)))
    col = 0
    for j in preorder:
        chans = layouts[j]
        r = 0
        for i, c in enumerate(chans):
            if c in POSITION_CHANNELS:
                data[:, col + i] = translations[:, j, "XYZ".index(c[0])]
            else:
                data[:, col + i] = angles[j][:, r]
                r += 1
        col += len(chans)
    return data


def _offset_text(v: np.ndarray, precision: int) -> str:
    digits = max(precision, 6)
    parts = []
    for x in v:
        s = f"{float(x):.{digits}f}".rstrip("0").rstrip(".")
        parts.append("0" if s in ("-0", "") else s)
    return " ".join(parts)


_DIGITS = np.array([[ord(f"{i:03d}"[k]) for i in range(1000)] for k in range(3)], dtype=np.uint8)


def _put_digits(out: np.ndarray, col: int, values: np.ndarray, ndigits: int) -> None:
    """Write ``ndigits`` ASCII digits of ``values`` (integers < 10**ndigits), zero padded,
    into columns ``col .. col + ndigits`` of ``out`` (values × characters)."""
    if ndigits <= 9:
        values = values.astype(np.int32)  # int32 division is several times faster than int64
    rest, end = values, col + ndigits
    while ndigits > 0:
        if ndigits >= 3:
            rest, m = np.divmod(rest, 1000)
            for k in range(3):
                out[:, end - 3 + k] = np.take(_DIGITS[k], m)
            end, ndigits = end - 3, ndigits - 3
        else:
            rest, m = np.divmod(rest, 10)
            out[:, end - 1] = m + 48
            end, ndigits = end - 1, ndigits - 1


def _format_rows(data: np.ndarray, precision: int) -> str:
    """Rows of ``data`` as space-separated fixed-point numbers, one line each: the same text
    as ``"%.{precision}f"`` per value (correctly rounded, ties to even), except that
    negative zero is written without its sign. Vectorised: no Python work per value."""
    data = np.ascontiguousarray(data, dtype=float)
    n_rows, n_cols = data.shape
    x = data.ravel()
    a = np.abs(x)
    with np.errstate(over="ignore"):
        scaled = a * 10.0 ** precision
    if x.size == 0 or not np.isfinite(scaled).all() or scaled.max() >= 2.0 ** 52:
        fmt = " ".join([f"%.{precision}f"] * n_cols) + "\n"
        data = np.where(np.abs(data) <= 0.5 * 10.0 ** -precision, 0.0, data)  # no "-0.000000"
        return "".join(fmt % tuple(row) for row in data.tolist())
    q = np.rint(scaled)
    # ``scaled`` is rounded; only where it lands exactly on a half can that rounding change
    # the decimal rounding of the true value: settle those few exactly.
    halves = np.flatnonzero(scaled - np.floor(scaled) == 0.5).tolist()
    if halves:
        from decimal import ROUND_HALF_EVEN, Decimal  # here: most outputs have no such value

    for i in halves:
        q[i] = float(Decimal(float(a[i])).scaleb(precision).to_integral_value(ROUND_HALF_EVEN))
    q = q.astype(np.int64)
    whole, frac = np.divmod(q, 10 ** precision)
    nwhole = len(str(int(whole.max())))
    width = 1 + nwhole + (1 + precision if precision else 0) + 1
    chars = np.empty((x.size, width), dtype=np.uint8)  # one row per value; 0 = no character
    chars[:, 0] = ((x < 0) & (q != 0)) * np.uint8(45)  # '-'
    _put_digits(chars, 1, whole, nwhole)
    for k in range(1, nwhole):  # drop leading zeros of the whole part
        np.multiply(chars[:, nwhole - k], whole >= 10 ** k, out=chars[:, nwhole - k])
    if precision:
        chars[:, 1 + nwhole] = 46  # '.'
        _put_digits(chars, 2 + nwhole, frac, precision)
    chars[:, -1] = 32
    chars[n_cols - 1::n_cols, -1] = 10
    flat = chars.ravel()
    return flat[flat != 0].tobytes().decode("ascii")
