"""controller/cli/outputs.py: output paths are checked before work and written atomically."""

import os
from pathlib import Path

import pytest

from controller.cli.outputs import (
    atomic_file,
    atomic_text,
    check_output_file,
    check_output_folder,
    partial_folder,
    publish_folder,
    staged_folder,
    write_text,
)
from controller.cli.support import ToolError


@pytest.fixture
def inputs(tmp_path):
    video = tmp_path / "in.avi"
    video.write_bytes(b"recording")
    folder = tmp_path / "frames"
    folder.mkdir()
    (folder / "f0.png").write_bytes(b"image")
    return video, folder


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob("*partial*"))


@pytest.mark.parametrize(
    "make_out,message",
    [
        (lambda t: t / "in.avi", "is the input"),
        (lambda t: t / "sub" / ".." / "in.avi", "is the input"),
        (lambda t: t / "frames" / "f0.png", "inside the input folder"),
        (lambda t: t / "frames" / "new.csv", "inside the input folder"),
        (lambda t: t / "frames", "is a folder"),
        (lambda t: Path("/dev/full"), "not a regular file"),
        (lambda t: t / "in.avi" / "x.csv", "is a file, so the folder"),
    ],
)
def test_bad_output_files_are_refused(tmp_path, inputs, make_out, message):
    with pytest.raises(ToolError, match=message):
        check_output_file(make_out(tmp_path), inputs)


def test_a_link_to_an_input_is_the_input(tmp_path, inputs):
    video, _ = inputs
    (tmp_path / "hard.avi").hardlink_to(video)
    (tmp_path / "soft.avi").symlink_to(video)
    for name in ("hard.avi", "soft.avi"):
        with pytest.raises(ToolError, match="is the input"):
            check_output_file(tmp_path / name, inputs)
    assert video.read_bytes() == b"recording"


def test_an_output_folder_may_not_hold_an_input_or_exist_when_new(tmp_path, inputs):
    with pytest.raises(ToolError, match="contains the input"):
        check_output_folder(tmp_path, inputs)
    with pytest.raises(ToolError, match="already exists"):
        check_output_folder(tmp_path / "frames", (), must_not_exist=True)
    with pytest.raises(ToolError, match="is a file"):
        check_output_folder(tmp_path / "in.avi")
    assert check_output_folder(tmp_path / "new" / "deeper", inputs) == tmp_path / "new" / "deeper"
    assert not (tmp_path / "new").exists()  # checked, not created


def test_an_unwritable_place_is_refused_before_work(tmp_path):
    with pytest.raises(ToolError, match="cannot write in '/proc'"):
        check_output_file(Path("/proc/no-such-folder/out.csv"))


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_folder_without_write_permission_is_refused(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        with pytest.raises(ToolError, match="cannot write in"):
            check_output_file(locked / "out.csv")
    finally:
        locked.chmod(0o700)
    kept = tmp_path / "kept.csv"
    kept.write_text("mine")
    kept.chmod(0o444)
    with pytest.raises(ToolError, match="is read-only"):
        check_output_file(kept)


@pytest.mark.parametrize("error", [RuntimeError, KeyboardInterrupt])
def test_a_failed_write_keeps_the_previous_result_and_leaves_nothing(tmp_path, error):
    out = tmp_path / "out.csv"
    out.write_text("previous good result\n")
    with pytest.raises(error), atomic_text(out) as handle:
        handle.write("half a new res")
        raise error()
    assert out.read_text() == "previous good result\n"
    assert leftovers(tmp_path) == []


def test_a_complete_write_replaces_the_result_with_normal_permissions(tmp_path):
    out = tmp_path / "sub" / "chart.png"
    with atomic_file(out) as temporary:
        assert temporary.parent == out.parent and temporary.suffix == ".png"
        assert temporary.name.startswith(".chart.png.")
        temporary.write_bytes(b"png")
    write_text(tmp_path / "a.md", "text")
    assert out.read_bytes() == b"png" and (tmp_path / "a.md").read_text() == "text"
    umask = os.umask(0)
    os.umask(umask)
    assert (out.stat().st_mode & 0o777) == 0o666 & ~umask
    assert leftovers(tmp_path) == []


def test_a_folder_is_published_whole_and_replaces_the_old_one_only_then(tmp_path):
    target = tmp_path / "dataset"
    partial = partial_folder(target)
    (partial / "meta.yaml").write_text("new")
    assert not target.exists()
    publish_folder(partial, target, replace=False)
    assert (target / "meta.yaml").read_text() == "new"
    again = partial_folder(target)
    (again / "meta.yaml").write_text("newer")
    with pytest.raises(FileExistsError):
        publish_folder(again, target, replace=False)
    publish_folder(again, target, replace=True)
    assert (target / "meta.yaml").read_text() == "newer"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dataset"]


def test_staged_files_move_into_place_only_on_success(tmp_path):
    (tmp_path / "REPORT.md").write_text("old")
    with pytest.raises(KeyboardInterrupt), staged_folder(tmp_path) as staging:
        (staging / "REPORT.md").write_text("half")
        raise KeyboardInterrupt
    assert (tmp_path / "REPORT.md").read_text() == "old"
    with staged_folder(tmp_path) as staging:
        (staging / "figures").mkdir()
        (staging / "figures" / "a.png").write_bytes(b"png")
        (staging / "REPORT.md").write_text("new")
    assert (tmp_path / "REPORT.md").read_text() == "new"
    assert (tmp_path / "figures" / "a.png").read_bytes() == b"png"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["REPORT.md", "figures"]


def test_refusals_of_unwritable_places_as_the_os_reports_them(tmp_path, monkeypatch):
    """The same checks as above, for a user without permission, when the tests run as root:
    the OS's answers are stood in for."""
    import controller.cli.outputs as outputs

    kept = tmp_path / "kept.csv"
    kept.write_text("mine")
    monkeypatch.setattr(outputs.os, "access", lambda path, mode: False)
    with pytest.raises(ToolError, match="is read-only"):
        check_output_file(kept)
    monkeypatch.undo()

    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(outputs.tempfile, "TemporaryFile", denied)
    with pytest.raises(ToolError, match=r"cannot write in '.*' \(Permission denied\)"):
        check_output_file(tmp_path / "new" / "out.csv")
    assert kept.read_text() == "mine"
