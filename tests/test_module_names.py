"""No module name stands for two things: a basename (``__init__.py`` aside) appears once across
the project's packages, so a name in a traceback, a doc or a conversation says which module
it is."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("controller", "core", "drivers", "evaluation")


def repeated_basenames(root: Path, packages: tuple[str, ...]) -> dict[str, list[str]]:
    """Basename -> the paths (relative to ``root``) of every module of ``packages`` that bears
    it, for the basenames borne by more than one module."""
    where: dict[str, list[str]] = defaultdict(list)
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            if path.name != "__init__.py":
                where[path.name].append(str(path.relative_to(root)))
    return {name: paths for name, paths in sorted(where.items()) if len(paths) > 1}


def test_no_module_name_repeats_across_the_packages():
    assert repeated_basenames(ROOT, PACKAGES) == {}


def test_a_repeated_name_is_found(tmp_path):
    for path in ("a/report.py", "b/c/report.py", "a/__init__.py", "b/__init__.py", "a/x.py"):
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path).write_text("")
    found = repeated_basenames(tmp_path, ("a", "b"))
    assert found == {"report.py": ["a/report.py", "b/c/report.py"]}
