"""Reading and writing the user's files safely.

Reading: only regular files, and never more than a cap. ``/dev/zero`` would grow
without end and a FIFO would block forever, so both are refused *before* any
byte is read (a non-blocking open tells a FIFO from a file without waiting for
a writer).

Writing: to a temporary file in the same directory, then an atomic rename, so
a failed write (disk full, killed process) never leaves a truncated file where
the user expects a good one.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat
from pathlib import Path


class FileError(ValueError):
    """A file that cannot be read or written; the message says which and why."""


def printable(text: str, limit: int) -> str:
    """User text (a file's key, a spec's path, a file name) as a message may print it:
    non-printable characters as \\uXXXX (an ESC in one had reached the terminal) and
    at most ``limit`` of the input's characters (a 900 kB key had come back whole)."""
    out = "".join(ch if ch.isprintable() else f"\\u{ord(ch):04x}" for ch in text[:limit])
    return out + ("…" if len(text) > limit else "")


def read_capped(path: str | Path, max_bytes: int) -> bytes:
    """The bytes of the regular file *path*, refusing anything else or anything larger.

    Parameters
    ----------
    path : the file to read.
    max_bytes : the largest size accepted, in bytes.

    Raises
    ------
    FileError
        If *path* is missing, not a regular file (directory, FIFO, device,
        socket), or larger than *max_bytes* (checked on the size the file
        declares and again on the bytes actually read, for files that grow).
    """
    path = Path(path)
    shown = printable(str(path), 300)
    try:
        # O_NONBLOCK: opening a FIFO with no writer returns at once instead of waiting.
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise FileError(f"cannot read {shown}: {exc.strerror}") from None
    except ValueError:  # an embedded NUL: no file has such a name
        raise FileError(f"cannot read {shown}: a file name holds no NUL character") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise FileError(f"{shown}: not a regular file")
        if info.st_size > max_bytes:
            raise FileError(f"{shown}: {info.st_size} bytes; the limit is {max_bytes}")
        chunks, size = [], 0
        while size <= max_bytes and (chunk := os.read(fd, max_bytes + 1 - size)):
            chunks.append(chunk)
            size += len(chunk)
        data = b"".join(chunks)
    except OSError as exc:
        raise FileError(f"cannot read {shown}: {exc.strerror}") from None
    finally:
        os.close(fd)
    if len(data) > max_bytes:
        raise FileError(f"{shown}: more than {max_bytes} bytes; the limit is {max_bytes}")
    return data


def regular_file(path: str | Path) -> Path:
    """*path*, once it is known to be a regular file (links followed), for a reader that
    opens it itself (pyarrow); FileError otherwise: a FIFO would block the reader
    forever (a review: ``pareto`` on a FIFO hung), a device would never end."""
    shown = printable(str(path), 300)
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        raise FileError(f"cannot read {shown}: {exc.strerror}") from None
    except ValueError:  # an embedded NUL
        raise FileError(f"cannot read {shown}: a file name holds no NUL character") from None
    if not stat.S_ISREG(mode):
        raise FileError(f"cannot read {shown}: not a regular file")
    return Path(path)


def write_atomic(path: str | Path, data: bytes) -> None:
    """Write *data* to *path* all or nothing: a temporary file, flushed, then renamed.

    Raises FileError naming the path when the directory is missing or read-only,
    the disk is full, or *path* is a directory. An existing file at *path* is
    left untouched unless the whole write succeeded.
    """
    write_all_atomic([(path, data)])


def write_all_atomic(files: list[tuple[str | Path, bytes]]) -> None:
    """Write several files all or none: every one is written to a temporary file beside
    its target first, and only when all of them are on disk are they renamed into
    place (a missing directory for the third file leaves the first two untouched). If
    a rename fails midway (a target another user owns in a sticky directory), the
    files already replaced get their old contents back from hard links kept for that.
    Raises FileError naming the path that could not be written."""
    staged: list[tuple[str, Path]] = []
    kept: dict[Path, str | None] = {}  # target -> a hard link to its old file, or None
    done: list[Path] = []
    try:
        for path, data in files:
            target = _target(Path(path))
            staged.append((_stage(target, data), target))
        for tmp, path in staged:
            kept[path] = _keep(path, tmp)
        for tmp, path in staged:
            try:
                os.replace(tmp, path)
            except OSError as exc:
                _restore(done, kept)
                raise FileError(f"cannot write {path}: {exc.strerror}") from None
            done.append(path)
    finally:
        for name in [tmp for tmp, _ in staged] + [k for k in kept.values() if k]:
            if os.path.lexists(name):
                os.unlink(name)


def _target(path: Path) -> Path:
    """The file a write to *path* replaces: a link's target (the link stays a link, as
    a shell's ``>`` keeps it), which must be a regular file or none. A FIFO, a device
    or a socket is refused: a rename would have put a plain file in its place (a
    review: ``--out`` on a FIFO replaced it). So is a path that leads through /dev or
    /proc (``/dev/stdout``, ``/dev/fd/1``): it names a process's stream, and the rename
    had replaced the file the shell sent it to (a review: ``--json /dev/stdout >>
    all.log`` lost the log's lines)."""
    if _through_streams(path):
        raise FileError(
            f"cannot write {path}: it lies under /dev or /proc (a device or a process's "
            "stream), not a file: give the file's own name"
        )
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return path
    except OSError as exc:
        raise FileError(f"cannot write {path}: {exc.strerror}") from None
    if stat.S_ISDIR(mode):
        raise FileError(f"cannot write {path}: it is a directory")
    if not stat.S_ISREG(mode):
        raise FileError(f"cannot write {path}: not a regular file (a FIFO, device or socket)")
    return path


def write_target(path: str | Path) -> Path:
    """The file a write to *path* would replace (a link's target), or FileError if it
    cannot be one: a directory, a FIFO, a device, a stream. For a command to check its
    output before its work (write_atomic checks it again)."""
    return _target(Path(path))


def _through_streams(path: Path) -> bool:
    """Whether *path*, or a link on the way to its file, or the folder it is in (a
    link to /proc/self/fd: a review), lies under /dev or /proc."""
    streams = {"dev", "proc"}
    here = Path(os.path.abspath(path))
    for _ in range(40):  # (the kernel's own limit on links followed)
        folder = Path(os.path.realpath(here.parent))
        if any(p.parts[1:2] and p.parts[1] in streams for p in (here, folder)):
            return True
        if not here.is_symlink():
            return False
        here = Path(os.path.abspath(here.parent / os.readlink(here)))
    return False


def _keep(path: Path, tmp: str) -> str | None:
    """A hard link to the file (or link) now at *path*, beside it; None if there is
    none or the file system cannot link (then a failed export cannot give it back)."""
    if not os.path.lexists(path):
        return None
    backup = f"{tmp}.old"
    try:
        os.link(path, backup, follow_symlinks=False)
    except OSError:
        return None
    return backup


def _restore(done: list[Path], kept: dict[Path, str | None]) -> None:
    """Undo the renames already made: the old file back, or no file where none was."""
    for path in done:
        old = kept.get(path)
        with contextlib.suppress(OSError):
            if old is not None:
                os.replace(old, path)
            else:
                os.unlink(path)


def _stage(path: Path, data: bytes) -> str:
    """*data* in a flushed temporary file beside *path*; returns its name. Its mode is
    the file's it replaces, else what the user's umask gives a new file (a security
    review: a 0600 file had come back 0644 under umask 077)."""
    directory = path.parent if str(path.parent) else Path(".")
    if path.is_dir():
        raise FileError(f"cannot write {path}: it is a directory")
    try:
        fd, tmp = _new_file(directory / _stem(path.name))
    except OSError as exc:
        raise FileError(f"cannot write {path}: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        with contextlib.suppress(FileNotFoundError):
            os.chmod(tmp, stat.S_IMODE(os.stat(path).st_mode))
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise FileError(f"cannot write {path}: {exc.strerror}") from None
    return tmp


def _stem(name: str) -> str:
    """The temporary file's stem for a target called *name*: ``.name``, or a fixed
    ``.camcore`` where that, with the random suffix and ``.old``, would pass the 255
    bytes a file name may have (a review: a valid 250-character name was refused as
    "File name too long")."""
    stem = f".{name}"
    return stem if len(os.fsencode(stem)) + len(".123456789abc.tmp.old") <= 255 else ".camcore"


def _new_file(stem: Path) -> tuple[int, str]:
    """A new file ``stem.<random>.tmp`` opened for writing, made as ``open`` makes one
    (mode 0666 less the umask; mkstemp's is 0600)."""
    for _ in range(100):
        name = f"{stem}.{secrets.token_hex(6)}.tmp"
        try:
            return os.open(name, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666), name
        except FileExistsError:
            continue
    raise FileExistsError(errno.EEXIST, "no free temporary name", str(stem))


def same_file(a: str | Path, b: str | Path) -> bool:
    """Whether two paths name the same file (existing or not), after resolving links."""
    pa, pb = Path(a), Path(b)
    try:
        if pa.exists() and pb.exists():
            return os.path.samefile(pa, pb)
    except OSError:
        pass
    return pa.resolve() == pb.resolve()
