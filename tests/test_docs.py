"""The documentation's shape: the README and the design short enough to read, docs/ within
its budget, no development history where users read (the product speaks of the product),
and every relative link in the README and docs/ pointing at a file that exists."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"

README_LINES = 150
ARCHITECTURE_LINES = 400
DOCS_LINES = 3000

# The words for a working session or a tracker's ticket, followed by its number:
# development history. Built from parts so that this file's own
# source does not read as a match.
HISTORY = re.compile(r"\b(" + "sess" + "ion|iss" + r"ue)\s*#?\d+", re.IGNORECASE)
CODE_FOLDERS = ("core", "controller", "drivers", "evaluation", "scripts", "tests")
CODE_SUFFIXES = {".py", ".yaml", ".yml", ".toml", ".md"}
# [text](target) and ![alt](target); a target may carry a title or an anchor
LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")


def _lines(path: Path) -> int:
    return len(path.read_text(encoding="utf-8").splitlines())


def _markdown() -> list[Path]:
    return [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


def _read_by_users() -> list[Path]:
    files = [ROOT / "README.md", ROOT / "Makefile", ROOT / "pyproject.toml"]
    files += [p for p in sorted(DOCS.rglob("*")) if p.is_file() and p.suffix in CODE_SUFFIXES]
    files += [p for p in sorted((ROOT / "configs").rglob("*")) if p.is_file()]
    for folder in CODE_FOLDERS:
        files += [
            p for p in sorted((ROOT / folder).rglob("*"))
            if p.is_file() and p.suffix in CODE_SUFFIXES and "node_modules" not in p.parts
        ]  # fmt: skip
    return files


def test_the_readme_and_the_design_are_short_and_docs_within_budget():
    assert _lines(ROOT / "README.md") <= README_LINES
    assert _lines(DOCS / "ARCHITECTURE.md") <= ARCHITECTURE_LINES
    total = {p.name: _lines(p) for p in sorted(DOCS.glob("*.md"))}
    assert sum(total.values()) <= DOCS_LINES, total


def test_no_development_history_where_users_read():
    found = []
    for path in _read_by_users():
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            continue
        for number, line in enumerate(text.splitlines(), 1):
            if HISTORY.search(line):
                found.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()[:100]}")
    assert not found, "\n".join(found)


def test_every_relative_link_in_the_readme_and_docs_resolves():
    broken = []
    for path in _markdown():
        text = re.sub(r"^```.*?^```", "", path.read_text(encoding="utf-8"), flags=re.S | re.M)
        for target in LINK.findall(text):
            if re.match(r"[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
                continue  # a URL (http:, mailto:) or an anchor in the same page
            file = target.split("#", 1)[0]
            if not (path.parent / file).exists():
                broken.append(f"{path.relative_to(ROOT)}: {target}")
    assert not broken, "\n".join(broken)


def test_no_doc_points_outside_the_repository():
    outside = re.compile(r"\.\./shared|/work/|\bscratch\b")
    found = [
        f"{path.relative_to(ROOT)}:{number}"
        for path in _markdown()
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if outside.search(line)
    ]
    assert not found, found
