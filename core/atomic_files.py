"""Files written atomically: a result replaces its destination only when complete.

``atomic_file`` / ``atomic_text`` / ``write_text`` write to a hidden temporary file in the
destination folder (``.NAME.XXXXXXXX.partial.EXT``), flush it to disk, then ``os.replace``
it over the destination. An error or an interruption removes the temporary file: the
destination is either the previous content or the complete new one, never a truncated file
under its name. The product's recorders and the offline tools share it.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TextIO

PathLike = Path | str


def hidden_sibling(path: Path, kind: str) -> Path:
    return path.parent / f".{path.name}.{secrets.token_hex(4)}.{kind}{path.suffix}"


def fsync_file(path: Path) -> None:
    """Flush the file at ``path`` to disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextmanager
def atomic_file(path: PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same folder, same suffix, so libraries that
    pick a format from the suffix still work); when the block succeeds, flush it to disk and
    rename it over ``path``; on any exception or interruption, remove it. An OSError that
    names no file (a write on a full disk) is raised naming ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = hidden_sibling(path, "partial")
    os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    try:
        yield temporary
        fsync_file(temporary)
        os.replace(temporary, path)
    except OSError as error:
        temporary.unlink(missing_ok=True)
        if error.filename is None:
            raise OSError(error.errno, error.strerror, str(path)) from error
        raise
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_text(path: PathLike, newline: str | None = None) -> Iterator[TextIO]:
    """A text file handle whose content replaces ``path`` only when the block succeeds."""
    with atomic_file(path) as temporary, open(temporary, "w", newline=newline) as handle:
        yield handle


def write_text(path: PathLike, text: str) -> None:
    """Replace ``path`` with ``text``, atomically."""
    with atomic_text(path) as handle:
        handle.write(text)
