"""Atomic file output: write to a temporary file in the destination folder, then rename over the target.

A failed or interrupted write never leaves a partial file under the target name.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterator
from pathlib import Path

from .errors import OutputError

__all__ = ["atomic_path"]


def _create_temporary(target: Path, folder: Path) -> Path:
    """Create an empty, unique hidden file beside ``target`` with the permissions a plain ``open()`` would give.

    ``os.open(..., 0o666)`` lets the kernel apply the process umask, so no thread ever changes the umask (reading
    it with ``os.umask`` means setting it, which races with other threads creating files).
    """
    for _ in range(100):
        name = folder / f".{target.stem}.{secrets.token_hex(4)}.tmp{target.suffix}"
        try:
            fd = os.open(name, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        except FileExistsError:
            continue
        except OSError as exc:
            raise OutputError(f"cannot write {target}: {exc.strerror or exc}") from exc
        os.close(fd)
        return name
    raise OutputError(f"cannot write {target}: no free temporary name in {folder}")  # pragma: no cover


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Context manager yielding a temporary path beside ``path``; on success it is renamed to ``path``.

    The temporary name keeps the target's suffix so writers that dispatch on the extension still work.
    On any exception the temporary file is removed and the target is left as it was.

    Raises
    ------
    OutputError
        If the destination folder does not exist or is not writable.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"cannot write {target}: folder {folder} does not exist")
    tmp = _create_temporary(target, folder)
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
