"""Files written whole or not at all: a temporary file beside the target, renamed over it;
folders replaced whole (:func:`atomic_folder`); output paths checked before any work
(:func:`output_dir`, :func:`output_file`); and paths a file names kept inside its folder
(:func:`within`), so a library someone sends cannot make us read or write elsewhere."""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
import unicodedata
from pathlib import Path
from typing import Callable, Iterable, Iterator

from doodle.core.errors import DoodleError

NAME_MAX = 255  # bytes in one file name (Linux, macOS, Windows)
PATH_MAX = 1024  # characters in a path a file names (far more than any library needs)


@contextlib.contextmanager
def atomic_path(path) -> Iterator[str]:
    """Yield the name of a temporary file beside ``path`` (same suffix, so writers that go by
    it pick the right format) and rename it to ``path`` when the block succeeds, keeping an
    existing file's mode. On any exception the temporary file is removed, an existing
    ``path`` is untouched, and the exception propagates (OSError becomes DoodleError)."""
    try:
        with atomic_files() as staged:
            yield staged(path)
    except OSError as exc:
        raise DoodleError(f"{path}: cannot write: {exc.strerror or exc}") from None


def atomic_write(path, chunks: Iterable[str] | bytes, sync: bool = True) -> None:
    """Write the text ``chunks`` (or one ``bytes``) to ``path`` atomically (:func:`atomic_path`),
    synced to the disk before the rename unless ``sync`` is False (a file that may be lost in
    a power cut, as a cache entry that is rebuilt when it cannot be read back)."""
    binary = isinstance(chunks, bytes)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") if binary else open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            for text in [chunks] if binary else chunks:
                fh.write(text)
            fh.flush()
            if sync:
                os.fsync(fh.fileno())


@contextlib.contextmanager
def atomic_files() -> Iterator[Callable[[object], str]]:
    """Several files written as one output (a compiled scene's BVH files, report and
    pictures): ``staged(path)`` names a temporary file beside ``path`` to write instead;
    when the block succeeds every one is renamed over its ``path``, all at the end, so a
    failure half-way (a picture that cannot be drawn) leaves every earlier file as it was.
    On any exception the temporary files are removed."""
    pending: list[tuple[str, Path]] = []

    def staged(path) -> str:
        path = Path(path)
        directory = output_dir(path.parent if str(path.parent) else Path("."), path)
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix or ".tmp", dir=directory)
        except OSError as exc:
            raise DoodleError(f"{path}: cannot write: {exc.strerror or exc}") from None
        os.close(fd)
        pending.append((tmp, path))
        return tmp

    try:
        yield staged
        for tmp, path in pending:
            try:
                mode = os.stat(path).st_mode & 0o777
            except OSError:
                mode = 0o666 & ~_umask()
            try:
                os.chmod(tmp, mode)
                os.replace(tmp, path)
            except OSError as exc:
                raise DoodleError(f"{path}: cannot write: {exc.strerror or exc}") from None
    finally:
        for tmp, _ in pending:
            if os.path.exists(tmp):
                os.unlink(tmp)


# --- output paths -----------------------------------------------------------------------

def _not_a_folder(path: Path, wanted: Path) -> DoodleError:
    what = "is a broken link" if os.path.islink(path) else "is a file"
    return DoodleError(f"{path}: {what}, expected a folder" + (f" (to hold {wanted})" if path != wanted else ""))


def check_dir(path, wanted=None) -> Path:
    """``path`` as a folder that is there or can be made: every part of it that exists is a
    folder (else a DoodleError naming that part, and ``wanted``, what was to go there).
    Checked before the work, so a run that would fail to write says so at once and in one
    line (not as an error of the operating system half-way through)."""
    path = Path(path)
    for part in (path, *path.parents):
        if os.path.lexists(part):
            if not part.is_dir():
                raise _not_a_folder(part, Path(wanted) if wanted is not None else path)
            break
    return path


def output_dir(path, wanted=None) -> Path:
    """The folder ``path``, made (with its parents) if missing; DoodleError naming the part
    that is a file, or why it cannot be made."""
    path = check_dir(path, wanted)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DoodleError(f"{path}: cannot make the folder: {exc.strerror or exc}") from None
    return path


def output_file(path, overwrite: bool = False) -> Path:
    """``path`` as a file the user named for a command to write: not a folder, not there
    already unless ``overwrite`` (the one rule every command writing a named file follows:
    ``--overwrite`` to replace it), and in a folder that is there or can be made."""
    path = Path(path)
    if path.is_dir():
        raise DoodleError(f"{path}: is a folder, expected a file")
    if os.path.lexists(path) and not overwrite:
        raise DoodleError(f"{path}: already exists (pass --overwrite to replace it)")
    check_dir(path.parent if str(path.parent) else Path("."), path)
    return path


# --- folders replaced whole ---------------------------------------------------------------

def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux ``renameat2(RENAME_EXCHANGE)``); False where the
    system or the file system cannot."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    at_fdcwd, rename_exchange = -100, 2
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), str(b))


def _swap_in(stage: Path, path: Path) -> None:
    """Put the folder ``stage`` at ``path``; the folder that was there (if any) ends up at
    ``stage``. In one step where the system allows; else in two renames, so for an instant
    ``path`` is missing — never half of one folder and half of the other."""
    if not os.path.lexists(path):
        os.rename(stage, path)
        return
    if _exchange(stage, path):
        return
    old = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".old", dir=path.parent))
    os.rmdir(old)
    os.rename(path, old)
    try:
        os.rename(stage, path)
    except OSError:
        os.rename(old, path)
        raise
    os.rename(old, stage)


def _link_tree(src: Path, dst: Path, fresh) -> None:
    """``src``'s content into the empty folder ``dst``, files as hard links (copies where the
    file system has none), symbolic links as links; top-level names in ``fresh`` left out."""
    def link(a, b):
        try:
            os.link(a, b, follow_symlinks=False)
        except OSError:
            shutil.copy2(a, b, follow_symlinks=False)

    for entry in os.scandir(src):
        if entry.name in fresh:
            continue
        target = dst / entry.name
        if entry.is_dir(follow_symlinks=False):
            shutil.copytree(entry.path, target, symlinks=True, copy_function=link)
        else:
            link(entry.path, target)


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_folder(path, fresh: Iterable[str] = ()) -> Iterator[Path]:
    """Replace the folder ``path`` whole or not at all: yield a staging folder beside it (a
    dot-folder) holding what ``path`` holds — less the top-level names in ``fresh``, which
    the caller writes anew — and when the block succeeds, swap it in for ``path`` (in one
    step on Linux). On any exception ``path`` is left exactly as it was and the staging
    folder removed. A killed run leaves at most a dot-folder beside ``path``.

    Files in the staging folder are hard links to the old ones: replace them (write a new
    file and rename it over, as :func:`atomic_write` does), never write into them."""
    path = check_dir(path)
    real = Path(os.path.realpath(path))  # a link to the folder stays a link: the folder it names is replaced
    parent = output_dir(real.parent)
    try:
        stage = Path(tempfile.mkdtemp(prefix=f".{real.name}.", suffix=".new", dir=parent))
    except OSError as exc:
        raise DoodleError(f"{path}: cannot write beside it: {exc.strerror or exc}") from None
    try:
        try:
            os.chmod(stage, (os.stat(real).st_mode if real.is_dir() else 0o777 & ~_umask()) & 0o7777)
            if real.is_dir():
                _link_tree(real, stage, set(fresh))
        except OSError as exc:
            raise DoodleError(f"{path}: cannot copy it to update it: {exc.strerror or exc}") from None
        yield stage
        try:
            _swap_in(stage, real)
        except OSError as exc:
            raise DoodleError(f"{path}: cannot replace it: {exc.strerror or exc}") from None
    finally:
        shutil.rmtree(stage, ignore_errors=True)


# --- paths a file names -------------------------------------------------------------------

def within(folder, relative, where: str) -> Path:
    """The path ``relative`` (as a file such as a library manifest names it) inside
    ``folder``: refused, in a DoodleError starting with ``where``, when it is absolute,
    uses ``\\`` or NUL, is absurdly long, or — links followed — leads out of ``folder``.
    A file someone sends must not make the program read or write anywhere else."""
    text = str(relative)
    shown = repr(text if len(text) <= 60 else text[:57] + "...")
    if not text or any(unicodedata.category(c) == "Cc" for c in text):  # NUL, line breaks, …
        raise DoodleError(f"{where}: {shown} is not a usable path (empty, or holds control characters such as NUL)")
    if "\\" in text:
        raise DoodleError(f"{where}: {shown}: use / between folders, not \\")
    if len(text) > PATH_MAX or any(len(part.encode("utf-8", "surrogateescape")) > NAME_MAX for part in text.split("/")):
        raise DoodleError(f"{where}: {shown}: too long ({len(text)} characters; a name may have at most "
                          f"{NAME_MAX} bytes, a path {PATH_MAX} characters)")
    if text.startswith("/") or (len(text) > 1 and text[1] == ":" and text[0].isalpha()):  # C:/…
        raise DoodleError(f"{where}: {shown} is an absolute path; paths are relative to the folder {folder}")
    base = Path(os.path.realpath(folder))
    path = Path(os.path.realpath(base / text))
    if path != base and base not in path.parents:
        raise DoodleError(f"{where}: {shown} leads out of the folder {folder}; only files inside it are read")
    return path


def safe_file_name(name: str, taken: Iterable[str] = (), limit: int = 100) -> str:
    """A file name (without suffix) for a name a user gave, such as an action's: letters,
    digits, spaces, ``-``, ``_`` and inner dots kept, anything else (``/``, ``\\``, ``..``
    at the start, control characters) made ``_``, at most ``limit`` characters, and not one
    of ``taken`` (``-2``, ``-3``… appended) — so a name never becomes a path elsewhere."""
    text = "".join(c if c.isalnum() or c in " -_." else "_" for c in unicodedata.normalize("NFC", name))
    text = text.strip(" .")[:limit].strip(" .") or "action"
    taken = {t.lower() for t in taken}
    stem, k = text, 1
    while text.lower() in taken:
        k += 1
        text = f"{stem[:limit - len(str(k)) - 1]}-{k}"
    return text
