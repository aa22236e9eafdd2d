"""Publishing make trials' comparisons: docs/TRIALS.md, the charts, and the report's trials
section refreshed in place."""

from pathlib import Path

import pytest

from controller.cli.support import ToolError
from evaluation.trials.publish import REPORT, SECTION, main, publish

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


def test_a_section_after_the_trials_is_kept(tmp_path):
    out, docs = tmp_path / "out", tmp_path / "docs"
    _comparison(out, "usb_c")
    docs.mkdir()
    (docs / REPORT).write_text(REPORT_BEFORE + "\n## 6. Later\n\nhand-written\n")
    publish(out, docs)
    report = (docs / REPORT).read_text()
    assert "old trials" not in report and "controllers compared (usb_c)" in report
    assert report.endswith("\n\n## 6. Later\n\nhand-written\n")
    publish(out, docs)  # a second publish changes nothing more
    assert (docs / REPORT).read_text() == report


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


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_publishing_a_second_task_keeps_the_first(tmp_path):
    first, second, docs = tmp_path / "first", tmp_path / "second", tmp_path / "docs"
    _comparison(first, "usb_c")
    _comparison(second, "usb_a")
    publish(first, docs)
    page = publish(second, docs).read_text()
    assert "(usb_a)" in page and "(usb_c)" in page
    assert page.index("(usb_a)") < page.index("(usb_c)")  # tasks in name order
    assert "](trials/usb_c/speed_success.png)" in page
    (second / "usb_a" / "comparison.md").write_text("## usb_a again\n\nno charts\n")
    page = publish(second, docs).read_text()  # a task published again is replaced whole
    assert "usb_a again" in page and "(usb_c)" in page
    assert sorted(p.name for p in (docs / "trials" / "usb_a").iterdir()) == ["comparison.md"]


def test_a_missing_chart_is_an_error_naming_it_and_nothing_is_written(tmp_path):
    out, docs = tmp_path / "out", tmp_path / "docs"
    _comparison(out, "usb_c")
    (out / "usb_c" / "speed_success.png").unlink()
    with pytest.raises(ToolError, match=r"comparison.md' links the chart 'speed_success.png'"):
        publish(out, docs)
    assert not docs.exists() or not any(docs.iterdir())


@pytest.mark.parametrize("bad", [REPORT, "trials/usb_a/comparison.md"])
def test_an_input_that_is_not_utf8_is_named_and_nothing_is_replaced(tmp_path, capsys, bad):
    first, second, docs = tmp_path / "first", tmp_path / "second", tmp_path / "docs"
    _comparison(first, "usb_a")
    docs.mkdir()
    (docs / REPORT).write_text(REPORT_BEFORE)
    publish(first, docs)
    (docs / bad).write_bytes(b"# Evaluation\n\xff\xfe broken\n")
    _comparison(second, "usb_c")
    before = _tree(docs)
    assert main([str(second), "--docs", str(docs)]) == 2
    err = capsys.readouterr().err
    assert (
        err == f"publish_trials: error: '{docs / bad}': not UTF-8 text (byte 0xff at "
        "offset 13); expected a markdown file\n"
    )
    assert _tree(docs) == before


def test_a_published_task_without_its_comparison_is_named(tmp_path):
    out, docs = tmp_path / "out", tmp_path / "docs"
    _comparison(out, "usb_c")
    (docs / "trials" / "usb_a").mkdir(parents=True)
    with pytest.raises(ToolError, match=r"trials/usb_a' holds no comparison.md"):
        publish(out, docs)
