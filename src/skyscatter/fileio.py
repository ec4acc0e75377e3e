"""Atomic file output: write to temporary files in the destination folder, then rename over the targets.

A failed or interrupted write never leaves a partial file under a target name, and a group of files (an EXR
and its PNG preview, a matrix as .npz and .csv, the panels of a figure) appears all together or not at all.

Temporary files are named ``.<target name>.<pid>.<token>.tmp<suffix>`` beside their target. They are removed
when the writing code raises (including ``KeyboardInterrupt``, and ``SIGTERM`` in the command line, which turns
it into an exception); a process killed outright (``SIGKILL``, power loss) leaves them behind, and the next
write into the same folder removes those whose process no longer runs (:func:`remove_stale_temporaries`).
Nothing here changes process-wide state (no ``umask`` toggling), so threads may write files concurrently.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import stat
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

from .errors import OutputError

__all__ = ["atomic_path", "atomic_paths", "build_lock", "check_output_path", "ensure_output_folder",
           "remove_stale_temporaries", "write_failure"]

# .<target name>.<pid>.<token>.<tmp|old><suffix>
_TEMP_RE = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.(?P<token>[0-9a-f]{12})\.(?P<kind>tmp|old)(?P<suffix>\.[^.]*)?$")


def _folder(target: Path) -> Path:
    return target.parent if str(target.parent) else Path(".")


def check_output_path(path: str | os.PathLike[str], *, option: str | None = None) -> Path:
    """Refuse an output path that cannot become a regular file, before any work is done.

    Checks that the path is not empty, is not an existing folder or special file, and that its folder exists,
    is a folder and is writable. ``option`` (e.g. ``"--out"``) prefixes the message. Returns the path.

    Raises
    ------
    OutputError
        Naming the path and what is wrong with it.
    """
    where = f"{option} " if option else ""
    if str(path) == "":
        raise OutputError(f"{where}'': an output path must name a file")
    target = Path(path)
    if target.is_dir() or str(target) in (".", "..") or str(path).endswith(os.sep):
        raise OutputError(f"{where}{path}: is a folder; give a file name")
    if target.exists() and not target.is_file():
        raise OutputError(f"{where}{path}: exists and is not a regular file")
    folder = _folder(target)
    if not folder.exists():
        raise OutputError(f"cannot write {where}{path}: folder {folder} does not exist")
    if not folder.is_dir():
        raise OutputError(f"cannot write {where}{path}: {folder} is not a folder")
    if not _accessible(folder):
        raise OutputError(f"cannot write {where}{path}: folder {folder} is not writable")
    return target


def ensure_output_folder(path: str | os.PathLike[str], *, what: str = "output folder", hint: str = "") -> Path:
    """Create the folder ``path`` (and its parents) if missing; refuse a file or a folder that cannot be written.

    ``what`` names it in messages (e.g. ``"--out-dir"``), ``hint`` is appended (e.g. how to choose another).

    Raises
    ------
    OutputError
    """
    folder = Path(path)
    tail = f"; {hint}" if hint else ""
    if folder.exists() and not folder.is_dir():
        raise OutputError(f"{what} {folder}: is a file, not a folder{tail}")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"{what} {folder}: cannot create the folder: {exc.strerror or exc}{tail}") from None
    if not _accessible(folder):
        raise OutputError(f"{what} {folder}: folder is not writable{tail}")
    return folder


def _accessible(folder: Path) -> bool:
    """Whether this process may create files in ``folder`` (effective ids and capabilities, where supported)."""
    if os.access in os.supports_effective_ids:
        return os.access(folder, os.W_OK | os.X_OK, effective_ids=True)
    return os.access(folder, os.W_OK | os.X_OK)


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists, owned by someone else
    return True


def remove_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove temporary files left in ``folder`` by skyscatter processes that no longer run.

    A leftover ``.tmp`` file is deleted. A leftover ``.old`` file (the previous version of a target, moved
    aside while a group was being committed) is put back under its target name if that name is free, else
    deleted. Files of running processes and files not named by this module are never touched. Returns the
    paths removed or restored.
    """
    base = Path(folder)
    done: list[Path] = []
    try:
        entries = list(os.scandir(base))
    except OSError:
        return done
    for entry in entries:
        m = _TEMP_RE.match(entry.name)
        if m is None or _pid_alive(int(m["pid"])):
            continue
        with contextlib.suppress(OSError):
            if not entry.is_file(follow_symlinks=False):
                continue
            path = Path(entry.path)
            target = base / m["name"]
            if m["kind"] == "old" and not target.exists():
                os.replace(path, target)
            else:
                path.unlink()
            done.append(path)
    return done


def write_failure(exc: OSError, targets: list[Path], temps: list[Path] | None = None) -> OutputError:
    """The one-line error for an OSError raised while writing ``targets`` (through ``temps``): names the target
    the failing file stands for (all of them when the error does not say which) and the reason, never a
    temporary file's name."""
    temps = temps or []
    names = [str(t) for t in targets]
    if exc.filename is not None and Path(exc.filename) in temps:
        names = [str(targets[temps.index(Path(exc.filename))])]
    reason = exc.strerror or str(exc) or type(exc).__name__
    for tmp, target in zip(temps, targets, strict=False):
        reason = reason.replace(str(tmp), str(target))
    code = exc.errno
    if code is None:  # a library that gave the reason only (OpenEXR): recognise the usual ones
        code = next((c for c in (errno.ENOSPC, errno.EFBIG, errno.EDQUOT) if os.strerror(c) in reason), None)
    if code in (errno.ENOSPC, errno.EDQUOT):
        reason += " (the disk or the quota is full)"
    elif code == errno.EFBIG:
        reason += " (the file system or the process's file size limit does not allow a file this large)"
    what = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
    return OutputError(f"cannot write {what}: {reason}; nothing was written")


def _new_temp(target: Path, kind: str) -> Path:
    """Create an empty temporary file beside ``target`` with the permissions ``open()`` would give it."""
    folder = _folder(target)
    for _ in range(100):
        name = f".{target.name}.{os.getpid()}.{os.urandom(6).hex()}.{kind}{target.suffix}"
        tmp = folder / name
        try:
            # mode 0o666 filtered by the process umask, as a plain open() does; no umask toggling.
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        except OSError as exc:
            raise OutputError(f"cannot write {target}: {exc.strerror or exc}") from None
        os.close(fd)
        return tmp
    raise OutputError(f"cannot write {target}: could not create a temporary file in {folder}")  # pragma: no cover


@contextlib.contextmanager
def atomic_paths(*paths: str | os.PathLike[str]) -> Iterator[list[Path]]:
    """Context manager yielding one temporary path per target; on success all are renamed into place.

    The temporary names keep their target's suffix, so writers that dispatch on the extension still work.
    Every target is checked first (:func:`check_output_path`). If the block raises (any exception, including
    ``KeyboardInterrupt``), the temporaries are removed and no target changes; an OSError (disk full, file too
    large, permission lost, I/O error) becomes an :class:`~skyscatter.errors.OutputError` naming the target
    (:func:`write_failure`). If renaming fails part way,
    the targets already renamed are restored to their previous versions (or removed if new). Errors name the
    targets, never the temporaries.

    Raises
    ------
    OutputError
        A target cannot be written (missing or read-only folder, a folder of that name, ...).
    """
    targets = [check_output_path(p) for p in paths]
    if len({t.resolve() for t in targets}) != len(targets):
        raise OutputError("the output files must differ: " + ", ".join(map(str, targets)))
    for folder in {_folder(t).resolve() for t in targets}:
        remove_stale_temporaries(folder)
    temps: list[Path] = []
    done: list[tuple[Path, Path | None]] = []  # (target, its moved-aside previous version or None)
    try:
        for t in targets:
            temps.append(_new_temp(t, "tmp"))
        try:
            yield list(temps)
        except OSError as exc:  # disk full, file too large, permission lost, I/O error... while writing
            raise write_failure(exc, targets, temps) from exc
        if len(targets) == 1:
            try:
                os.replace(temps[0], targets[0])
            except OSError as exc:
                raise OutputError(f"cannot write {targets[0]}: {exc.strerror or exc}") from exc
            done.append((targets[0], None))
            return
        for target, tmp in zip(targets, temps, strict=True):
            backup = None
            try:
                if target.exists():
                    backup = _new_temp(target, "old")
                    os.replace(target, backup)
                os.replace(tmp, target)
            except OSError as exc:
                if backup is not None:
                    with contextlib.suppress(OSError):
                        if target.exists():
                            backup.unlink()
                        else:
                            os.replace(backup, target)
                raise OutputError(f"cannot write {target}: {exc.strerror or exc}") from exc
            done.append((target, backup))
    except BaseException:
        if len(targets) > 1:
            for target, backup in reversed(done):  # undo the renames of this group
                with contextlib.suppress(OSError):
                    if backup is not None:
                        os.replace(backup, target)
                    else:
                        target.unlink()
        for tmp in temps:
            with contextlib.suppress(OSError):
                tmp.unlink()
        raise
    for _, backup in done:
        if backup is not None:
            with contextlib.suppress(OSError):
                backup.unlink()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Context manager yielding a temporary path beside ``path``; on success it is renamed to ``path``.

    The single-file case of :func:`atomic_paths`: on any exception the temporary file is removed and the
    target is left as it was.

    Raises
    ------
    OutputError
        If the destination folder does not exist or is not writable, or ``path`` is a folder.
    """
    with atomic_paths(path) as (tmp,):
        yield tmp


class NumbaCacheWarning(UserWarning):
    """Numba's usual cache folders are not writable; compiled kernels are cached in a fallback folder."""


def _writable_dir(path: str) -> bool:
    """Whether ``path`` is (or can be created as) a folder this process can write, tested as numba does: by
    creating (and removing) a file in it. Without the tempfile module, whose import costs every command."""
    try:
        os.makedirs(path, exist_ok=True)
        probe = os.path.join(path, f".skyscatter-probe-{os.getpid()}-{os.urandom(6).hex()}")
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        os.unlink(probe)
    except OSError:
        return False
    return True


def _private_dir(path: str) -> bool:
    """Create or accept ``path`` only as a real folder owned by this user and writable by nobody else."""
    try:
        os.makedirs(path, mode=0o700, exist_ok=True)
        st = os.lstat(path)
    except OSError:
        return False

    return (stat.S_ISDIR(st.st_mode) and st.st_uid == os.getuid() and not st.st_mode & 0o022
            and _writable_dir(path))


def ensure_numba_cache(package_dir: str | os.PathLike[str]) -> str | None:
    """Give numba a writable cache folder when neither of its usual ones is writable.

    Numba caches compiled functions (``cache=True``) beside the source (``__pycache__``) or, if that is
    read-only (a system or container install), in the user's cache folder (``$XDG_CACHE_HOME/numba`` or
    ``~/.cache/numba``). If both are unwritable (HOME read-only or missing), numba refuses to compile
    (``RuntimeError: cannot cache function ...: no locator available``). This sets ``NUMBA_CACHE_DIR`` to a
    private folder in the system temporary folder (``skyscatter-numba-<uid>``; a fresh one if that name is
    taken by someone else) and warns once (:class:`NumbaCacheWarning`). A ``NUMBA_CACHE_DIR`` set by the user
    is always kept. Returns the folder chosen, or None when nothing needed changing.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    if _writable_dir(os.path.join(os.fspath(package_dir), "__pycache__")):
        return None
    user_cache = os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "numba")
    if not user_cache.startswith("~") and _writable_dir(user_cache):
        return None
    import tempfile

    uid = os.getuid() if hasattr(os, "getuid") else 0
    fallback = os.path.join(tempfile.gettempdir(), f"skyscatter-numba-{uid}")
    if not _private_dir(fallback):
        try:
            fallback = tempfile.mkdtemp(prefix=f"skyscatter-numba-{uid}-")
        except OSError:
            return None  # nowhere to write at all; numba will say so
    os.environ["NUMBA_CACHE_DIR"] = fallback
    config = sys.modules.get("numba.core.config")
    if config is not None:  # numba imported before skyscatter: it has read its settings already
        config.CACHE_DIR = fallback

    # warn_explicit with a file name that has no source line: the warning prints as one line.
    warnings.warn_explicit(
        f"numba cannot write its cache beside the package or in {user_cache}; caching compiled kernels in "
        f"{fallback} (set NUMBA_CACHE_DIR to choose)", NumbaCacheWarning, "skyscatter", 0,
    )
    return fallback


@contextlib.contextmanager
def build_lock(path: Path) -> Iterator[None]:
    """Hold the exclusive lock of the cached file ``path`` (``.NAME.lock`` beside it, :func:`fcntl.flock`) while it
    is looked up again and built: another process building it is waited for. The lock goes with its file
    descriptor, so the kernel releases it when the process ends, however it ends (no stale locks). Where the folder
    cannot be written there is no lock (the caller builds the file and warns that it is not cached)."""
    import fcntl

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path.with_name(f".{path.name}.lock"), os.O_RDWR | os.O_CREAT, 0o666)
    except OSError:
        yield
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock
