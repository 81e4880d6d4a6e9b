"""Reading ``.npz`` files a user hands us (effort models, shape files, height fields): every
array read eagerly, never a pickle, and every way a file can be broken said as what it is.

``np.load`` is the wrong tool for untrusted files: given bytes that are not a zip archive it
falls back to unpickling, so random bytes come back as advice to pass ``allow_pickle`` — the
wrong diagnosis — and an array header may announce any size, which ``np.load`` allocates
before finding the data missing. Here the archive must be a zip of ``.npy`` members, each
member's header is checked against the bytes that are really there before the array is
read, and any failure is a :class:`DoodleError` ``LABEL: not a valid .npz archive (…)``.
"""

from __future__ import annotations

import io
import re
import zipfile
import zlib
from pathlib import Path

import numpy as np

from doodle.core.errors import DoodleError

#: The largest archive member read (uncompressed bytes): far above any model, shape file or
#: height field, far below what would exhaust the memory of a laptop (a zip bomb).
MAX_MEMBER_BYTES = 1 << 30

# what reading a broken zip or npy member raises (zlib, zipfile, numpy's header parser)
_BROKEN = (ValueError, TypeError, OverflowError, KeyError, EOFError, OSError, RuntimeError, NotImplementedError,
           zipfile.BadZipFile, zlib.error, SyntaxError, IndexError)


# The header numpy writes for an array of a simple dtype (np.save, np.savez), e.g.
# ``{'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }`` padded with spaces: read
# by this expression (numpy's own parser compiles each header as Python, ~20 times slower).
# It accepts only text that numpy's parser reads the same way (a shape of decimal ints
# without leading zeros; a descr without quotes or escapes); anything else goes to numpy's.
_PLAIN = re.compile(r"\{'descr': '([<>|=]?[A-Za-z]\d*)', 'fortran_order': (False|True), "
                    r"'shape': \((|(?:0|[1-9]\d*),|(?:0|[1-9]\d*)(?:, (?:0|[1-9]\d*))+)\), \} *\n")
_LENGTH = {(1, 0): 2, (2, 0): 4}  # bytes of the header's length field, little-endian, by format version
_MAX_HEADER = 10000  # numpy's limit on a header's length (np.lib.format._MAX_HEADER_SIZE)


def _plain_header(buf: io.BytesIO, version: tuple) -> tuple[tuple, bool, np.dtype] | None:
    """What numpy's parser reads from a header of the :data:`_PLAIN` form, or None (another
    form, or too short or long: numpy's parser reads it, or says what is wrong)."""
    size = _LENGTH.get(version)
    if size is None:
        return None
    field = buf.read(size)
    if len(field) != size:
        return None
    length = int.from_bytes(field, "little")
    header = buf.read(length)
    if len(header) != length or length > _MAX_HEADER:
        return None
    plain = _PLAIN.fullmatch(header.decode("latin1"))
    if plain is None:
        return None
    descr, fortran, shape = plain.groups()
    return tuple(int(n) for n in shape.split(",") if n), fortran == "True", np.dtype(descr)


def _header(buf: io.BytesIO) -> tuple[tuple, bool, np.dtype]:
    """``(shape, fortran_order, dtype)`` of the ``.npy`` whose bytes ``buf`` holds."""
    version = np.lib.format.read_magic(buf)
    start = buf.tell()
    plain = _plain_header(buf, version)
    if plain is not None:
        return plain
    buf.seek(start)
    if version == (1, 0):
        return np.lib.format.read_array_header_1_0(buf)
    if version == (2, 0):
        return np.lib.format.read_array_header_2_0(buf)
    raise ValueError(f"unsupported .npy format version {version[0]}.{version[1]}")


def _array(data: bytes, name: str) -> np.ndarray:
    """The array of one member's bytes, its announced size checked before anything is allocated."""
    buf = io.BytesIO(data)
    shape, fortran, dtype = _header(buf)
    if dtype.hasobject:
        raise ValueError(f"array {name!r} holds Python objects, which this program never loads")
    count = 1
    for n in shape:
        count *= int(n)
    have = len(data) - buf.tell()
    if count * dtype.itemsize != have:
        raise ValueError(f"array {name!r} announces {count * dtype.itemsize} bytes of data but holds {have}")
    flat = np.frombuffer(data, dtype=dtype, count=count, offset=buf.tell()).copy()
    return flat.reshape(shape[::-1]).T if fortran else flat.reshape(shape)


def read_npz(path, label: str | None = None) -> dict[str, np.ndarray]:
    """Every array of the ``.npz`` at ``path``, by name (member name without ``.npy``).

    Raises DoodleError starting ``LABEL:`` (default: the path) when the file is missing, is
    not a zip archive of ``.npy`` arrays, is truncated or corrupt, or holds object arrays.
    """
    path = Path(path)
    label = str(path) if label is None else label
    if path.is_dir():
        raise DoodleError(f"{label}: is a directory, not a .npz file")
    try:
        handle = open(path, "rb")
    except FileNotFoundError:
        raise DoodleError(f"{label}: no such file") from None
    except OSError as exc:
        raise DoodleError(f"{label}: cannot read: {exc.strerror or exc}") from None
    arrays = {}
    try:
        with handle, zipfile.ZipFile(handle) as archive:
            for info in archive.infolist():
                if info.is_dir():
                    continue
                if not info.filename.endswith(".npy"):
                    raise ValueError(f"member {info.filename!r} is not a .npy array")
                if info.file_size > MAX_MEMBER_BYTES:
                    raise ValueError(f"member {info.filename!r} is {info.file_size} bytes uncompressed, "
                                     f"more than the {MAX_MEMBER_BYTES} read")
                name = info.filename[:-4]
                arrays[name] = _array(archive.read(info), name)
    except zipfile.BadZipFile as exc:
        if not arrays and not zipfile.is_zipfile(path):
            raise DoodleError(f"{label}: not a valid .npz archive (not a zip archive)") from None
        raise DoodleError(f"{label}: not a valid .npz archive ({exc})") from None
    except _BROKEN as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise DoodleError(f"{label}: not a valid .npz archive ({reason})") from None
    return arrays
