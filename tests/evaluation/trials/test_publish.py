"""Publishing make trials' comparisons: docs/TRIALS.md, the charts, and the report's trials
section refreshed in place."""

from pathlib import Path

import pytest

from evaluation.common.cli_support import ToolError
from evaluation.trials.publish import REPORT, SECTION, publish

REPORT_BEFORE = f"# Evaluation\n\n## 1. The calibration\n\nkept\n\n{SECTION}\n\nold trials\n"


def _comparison(out: Path, task: str) -> None:
    folder = out / task
    folder.mkdir(parents=True)
    (folder / "comparison.md").write_text(
        f"## Insertion trials: controllers compared ({task})\n\n| a |\n|---|\n| 1 |\n\n"
        "![success](speed_success.png)\n"
    )
    (folder / "speed_success.png").write_bytes(b"png")


def test_publish_writes_the_page_and_the_charts_and_refreshes_the_reports_section(tmp_path):
    out, docs = tmp_path / "out", tmp_path / "docs"
    _comparison(out, "usb_c")
    docs.mkdir()
    (docs / REPORT).write_text(REPORT_BEFORE)
    page = publish(out, docs)
    assert page.read_text().startswith("# Insertion trials")
    assert "](trials/usb_c/speed_success.png)" in page.read_text()
    assert (docs / "trials" / "usb_c" / "speed_success.png").read_bytes() == b"png"
    report = (docs / REPORT).read_text()
    assert report.startswith("# Evaluation\n\n## 1. The calibration\n\nkept\n\n" + SECTION)
    assert "old trials" not in report
    assert "### Insertion trials: controllers compared (usb_c)" in report  # one level down
    assert report.count(SECTION) == 1


def test_publish_leaves_a_report_without_the_section_and_creates_none(tmp_path):
    out, docs = tmp_path / "out", tmp_path / "docs"
    _comparison(out, "usb_a")
    docs.mkdir()
    publish(out, docs)
    assert not (docs / REPORT).exists()
    (docs / REPORT).write_text("# Evaluation\n\nno trials section\n")
    publish(out, docs)
    assert (docs / REPORT).read_text() == "# Evaluation\n\nno trials section\n"


def test_publish_without_comparisons_is_a_tool_error(tmp_path):
    with pytest.raises(ToolError, match="no <task>/comparison.md"):
        publish(tmp_path, tmp_path / "docs")


@pytest.mark.parametrize("where", ["the comparisons", "a file"])
def test_publish_refuses_docs_that_are_its_input_or_a_file(tmp_path, where):
    out = tmp_path / "out"
    _comparison(out, "usb_c")
    docs = out if where == "the comparisons" else out / "usb_c" / "comparison.md"
    with pytest.raises(ToolError, match="^--docs '"):
        publish(out, docs)
    assert not (out / "TRIALS.md").exists()
