"""Each trial's own record in a batch (``--records``): OUT/records/<controller>-<seed>/.

A trial writes its record into a hidden folder, ``records/.<controller>-<seed>.partial``
(its ``TrialSpec.out_dir``). The batch renames it to ``records/<controller>-<seed>`` right
after the trial's row is in ``trials.csv``, and never over an existing folder; when the batch
stops early, the hidden folders of the trials that did not finish are removed. So a record
under its own name is always a trial listed in ``trials.csv``; only a batch killed with
SIGKILL can leave hidden ``.partial`` folders: a resumed batch keeps those of the trials
with a row (killed between the row and the rename) and deletes the others.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from controller.cli.support import ToolError

RECORDS = "records"
PARTIAL = ".partial"


def record_name(controller: str, seed: int) -> str:
    return f"{controller}-{seed}"


def unfinished_record(records: Path, controller: str, seed: int) -> Path:
    """Where the trial writes its record until it is kept (see the module doc)."""
    return records / f".{record_name(controller, seed)}{PARTIAL}"


def kept_record(unfinished: Path) -> Path:
    """The name a trial's record is kept under (see the module doc)."""
    return unfinished.with_name(unfinished.name.removeprefix(".").removesuffix(PARTIAL))


def keep_record(unfinished: Path) -> None:
    """Give a finished trial's record its own name (nothing when the trial wrote none);
    ToolError if a folder of that name exists already."""
    if not unfinished.exists():
        return
    kept = kept_record(unfinished)
    if kept.exists() or kept.is_symlink():
        raise ToolError(f"'{kept}' exists already; a trial's record is never written over")
    os.rename(unfinished, kept)


def discard_unfinished_records(records: Path) -> None:
    """Remove the hidden folders of the trials that did not finish."""
    for folder in records.glob(f".*{PARTIAL}"):
        shutil.rmtree(folder, ignore_errors=True)
