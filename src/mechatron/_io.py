"""Writing files so that nothing is lost: all or nothing.

Every file Mechatron writes (simulation logs, plots, reports, generated C, FMUs, results
of estimation) goes through :func:`atomic_path`: the writer writes a temporary file in the
destination's folder, and only a complete file replaces the destination, with
:func:`os.replace` (atomic on POSIX and Windows within one file system). An interrupted run
(Ctrl-C, a full disk, an exception in the writer) leaves the previous file as it was and no
temporary file behind.

A folder is built the same way by :func:`atomic_dir`: in a temporary sibling, renamed to
its name when complete.

Only a killed process (``kill -9``, a power cut) can leave a temporary file or folder
behind (``.mechatron-tmp-<name>-...``); the next write of the same name removes those older
than :data:`STALE_AFTER`.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_path", "atomic_dir", "write_text", "write_bytes", "save_figure"]

log = logging.getLogger(__name__)

#: Temporary files and folders start with this, so that they are recognisable.
TEMP_PREFIX = ".mechatron-tmp-"

#: Leftovers of a killed writer older than this (s) are removed by the next write of the
#: same name; younger ones may belong to a writer still at work.
STALE_AFTER = 24 * 3600.0


def _remove_stale(folder: Path, prefix: str) -> None:
    """Remove temporary files and folders ``prefix*`` in ``folder`` older than
    :data:`STALE_AFTER` (left by a killed process)."""
    import time
    now = time.time()
    try:
        candidates = list(folder.glob(_glob_escape(prefix) + "*"))
    except OSError:
        return
    for p in candidates:
        try:
            if now - p.lstat().st_mtime < STALE_AFTER:
                continue
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p, ignore_errors=True)
            else:
                p.unlink()
            log.debug("removed stale temporary %s", p)
        except OSError:
            continue


def _glob_escape(text: str) -> str:
    """``text`` with the glob characters ``*?[`` taken literally."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in text)


@functools.cache
def _umask() -> int:
    """The process's umask (read without changing it where the system allows)."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    umask = os.umask(0o022)
    os.umask(umask)
    return umask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path in the folder of ``path``; ``path`` is replaced by it on success.

    The temporary name keeps the suffix of ``path`` (matplotlib and Pillow choose the
    format by the suffix). On success the file is flushed to disk, given the permissions
    of the file it replaces (or the usual ones of a new file) and renamed onto ``path``;
    on any exception, Ctrl-C included, it is removed and ``path`` is left untouched.

    Examples
    --------
    >>> with atomic_path("fig.png") as tmp:        # doctest: +SKIP
    ...     fig.savefig(tmp)
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    try:
        fd, name = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{path.stem}-",
                                    suffix=path.suffix, dir=folder)
    except OSError as exc:
        raise _naming(exc, path) from exc
    os.close(fd)
    tmp = Path(name)
    try:
        try:
            yield tmp
        except OSError as exc:       # name the destination, not the temporary file
            raise _naming(exc, path) from exc
        try:
            mode = stat.S_IMODE(os.stat(path).st_mode)
        except FileNotFoundError:
            mode = 0o666 & ~_umask()
        os.chmod(tmp, mode)
        with open(tmp, "rb+") as fh:      # a full disk shows here at the latest
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        log.info("wrote %s", path)
        _remove_stale(folder, f"{TEMP_PREFIX}{path.stem}-")
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def _naming(exc: OSError, path: Path) -> OSError:
    """``exc`` (same type) about ``path``: "[Errno 28] No space left on device: 'x.csv'"."""
    if exc.errno is None:
        return exc
    return type(exc)(exc.errno, exc.strerror or os.strerror(exc.errno), str(path))


def write_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` all or nothing (see :func:`atomic_path`)."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding=encoding)
    return path


def write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` all or nothing (see :func:`atomic_path`)."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return path


def save_figure(fig, path: str | os.PathLike[str], **options) -> Path:
    """``fig.savefig(path, **options)`` all or nothing (the format follows the suffix)."""
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, **options)
    return path


@contextlib.contextmanager
def atomic_dir(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A new temporary folder beside ``path``; it becomes ``path`` on success.

    If ``path`` exists, it is replaced as a whole (moved aside, the new folder renamed in,
    the old one deleted), so a reader sees either the old or the new content, never a mix.
    On any exception the temporary folder is deleted and ``path`` is left untouched.
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f"{TEMP_PREFIX}{path.name}-", dir=parent))
    except OSError as exc:
        raise _naming(exc, path) from exc
    old = None
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~_umask())
        if path.exists():
            old = Path(tempfile.mkdtemp(prefix=f"{TEMP_PREFIX}{path.name}-old-",
                                        dir=parent))
            os.replace(path, old / path.name)
            try:
                os.replace(tmp, path)
            except BaseException:
                os.replace(old / path.name, path)      # put the old folder back
                raise
        else:
            os.replace(tmp, path)
        log.info("wrote folder %s", path)
        _remove_stale(parent, f"{TEMP_PREFIX}{path.name}-")
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
