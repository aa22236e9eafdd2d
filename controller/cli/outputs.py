"""Where the tools write: output paths checked before any work, results written atomically.

Every tool that writes a result (CSV, YAML, PNG, markdown, a dataset folder) goes through
this module:

* ``check_output_file`` / ``check_output_folder`` run before any work. An output may not be
  one of the tool's inputs (same resolved path, or the same file under another name), lie
  inside an input folder, or (for a folder) contain an input; an existing output must be a
  regular file (a file path) or a folder (a folder path), never a device such as
  ``/dev/full``, nor a read-only file; its folder must exist or be creatable, and be
  writable (probed by creating a temporary file, which also catches read-only file
  systems).
* ``atomic_file`` / ``atomic_text`` / ``write_text`` (``core.atomic_files``, shared with the
  product's recorders) write to a hidden temporary file in the
  destination folder (``.NAME.XXXXXXXX.partial.EXT``), flush it to disk, then
  ``os.replace`` it over the destination. An error or an interruption removes the temporary
  file: the destination is either the previous result or the complete new one.
* ``partial_folder`` / ``publish_folder`` do the same for folders (``.NAME.XXXXXXXX.partial``
  renamed into place when complete); ``staged_folder`` moves a set of files into place
  together at the end of a run.

A process killed with SIGKILL leaves at most hidden ``*.partial*`` files or folders beside
the destination, never a truncated file under the destination's name.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from controller.cli.support import ToolError
from core.atomic_files import atomic_file, atomic_text, fsync_file, hidden_sibling, write_text

__all__ = [
    "atomic_file", "atomic_text", "check_output_file", "check_output_folder",
    "partial_folder", "publish_folder", "staged_folder", "write_text",
]  # fmt: skip

PathLike = Path | str


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _check_not_input(path: Path, inputs: Iterable[PathLike | None], option: str) -> None:
    target = path.resolve()
    for item in inputs:
        if item is None:
            continue
        source = Path(item).resolve()
        if target == source or _same_file(path, Path(item)):
            raise ToolError(
                f"{option} '{path}' is the input '{item}'; a tool never writes over its inputs"
            )
        if target.is_relative_to(source) and not source.is_file():
            raise ToolError(
                f"{option} '{path}' lies inside the input folder '{item}'; "
                "write the output somewhere else"
            )
        if source.is_relative_to(target):
            raise ToolError(
                f"{option} '{path}' contains the input '{item}'; write the output somewhere else"
            )


def _check_writable_folder(folder: Path, option: str) -> None:
    """The nearest existing ancestor of ``folder`` must be a folder we can create files in."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise ToolError(f"{option}: '{existing}' is a file, so the folder '{folder}' cannot exist")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as exc:
        raise ToolError(f"{option}: cannot write in '{existing}' ({exc.strerror})") from None


def check_output_file(
    path: PathLike, inputs: Iterable[PathLike | None] = (), option: str = "--out"
) -> Path:
    """Refuse an output file path that cannot or must not be written (see module doc)."""
    path = Path(path)
    if path.is_dir():
        raise ToolError(f"{option} '{path}' is a folder; expected a file path")
    if path.exists() and not path.is_file():
        raise ToolError(
            f"{option} '{path}' is not a regular file (a device, pipe or socket); "
            "expected a file path"
        )
    if path.is_file() and not os.access(path, os.W_OK):
        raise ToolError(f"{option} '{path}' is read-only; it is not replaced")
    _check_not_input(path, inputs, option)
    _check_writable_folder(path.parent, option)
    return path


def check_output_folder(
    path: PathLike,
    inputs: Iterable[PathLike | None] = (),
    option: str = "OUT",
    must_not_exist: bool = False,
) -> Path:
    """Refuse an output folder that cannot or must not be written; with ``must_not_exist``
    an existing path is refused too (the tool never merges into or replaces it)."""
    path = Path(path)
    if path.exists() or path.is_symlink():
        if must_not_exist:
            raise ToolError(
                f"{option} '{path}' already exists; choose a new folder (or remove it first)"
            )
        if not path.is_dir():
            raise ToolError(f"{option} '{path}' is a file; expected a folder")
    _check_not_input(path, inputs, option)
    _check_writable_folder(path, option)
    return path


def partial_folder(path: PathLike) -> Path:
    """Create a hidden folder beside ``path`` in which to build it (``publish_folder``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = hidden_sibling(path, "partial")
    partial.mkdir()
    return partial


def publish_folder(partial: Path, path: PathLike, replace: bool) -> None:
    """Rename the complete folder ``partial`` to ``path``. With ``replace``, an existing
    ``path`` is moved aside first and removed afterwards (never lost before the new one is
    in place); without it, an existing ``path`` is an error."""
    path = Path(path)
    if not path.exists():
        os.rename(partial, path)
        return
    if not replace:
        raise FileExistsError(17, "already exists; not replaced", str(path))
    old = hidden_sibling(path, "old")
    os.rename(path, old)
    os.rename(partial, path)
    shutil.rmtree(old, ignore_errors=True)


def discard_folder(partial: Path) -> None:
    shutil.rmtree(partial, ignore_errors=True)


@contextmanager
def staged_folder(root: PathLike) -> Iterator[Path]:
    """Yield a hidden staging folder inside ``root``; when the block succeeds, every file
    written under it is moved (``os.replace``, one by one) to the same relative path under
    ``root``. The staging folder is removed in any case."""
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(dir=root, prefix=".staging-", suffix=".partial"))
    try:
        yield staging
        for source in sorted(p for p in staging.rglob("*") if p.is_file()):
            target = root / source.relative_to(staging)
            target.parent.mkdir(parents=True, exist_ok=True)
            fsync_file(source)
            os.replace(source, target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
