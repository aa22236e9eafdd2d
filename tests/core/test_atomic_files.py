"""Atomic writes on a failing disk (a real OS error: a file size limit in a subprocess)."""

import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

LIMITED_WRITE = """
import resource, signal, sys
from pathlib import Path
from core.atomic_files import write_text

signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
resource.setrlimit(resource.RLIMIT_FSIZE, (10_000, 10_000))
try:
    write_text(Path(sys.argv[1]) / "result.csv", "x" * 50_000)
except OSError as error:
    print("error:", error)
"""


def test_a_failed_write_names_the_destination_and_leaves_nothing(tmp_path):
    (tmp_path / "result.csv").write_text("the previous result\n")
    ran = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(LIMITED_WRITE), str(tmp_path)],
        capture_output=True, text=True, cwd=ROOT, timeout=60,
    )  # fmt: skip
    assert ran.stdout.strip() == f"error: [Errno 27] File too large: '{tmp_path / 'result.csv'}'"
    assert (tmp_path / "result.csv").read_text() == "the previous result\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.csv"]
