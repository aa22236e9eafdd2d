"""The run's record on a failing disk: the files keep only whole rows, and the error names
the file (a real OS error: a file size limit, RLIMIT_FSIZE, in a subprocess)."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

LIMITED_RECORDER = """
import resource, signal, sys
from pathlib import Path
from controller.run.record import JsonLines

signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))
lines = JsonLines(Path(sys.argv[1]) / "ticks.jsonl", flush_every=100)
try:
    for k in range(100_000):
        lines.write({"k": k, "pad": "x" * 40})
    lines.close()
except OSError as error:
    print("error:", error)
"""


def test_a_failed_write_cuts_the_file_at_its_last_flush_and_names_it(tmp_path):
    ran = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(LIMITED_RECORDER), str(tmp_path)],
        capture_output=True, text=True, cwd=ROOT, timeout=60,
    )  # fmt: skip
    assert ran.returncode == 0, ran.stderr
    path = tmp_path / "ticks.jsonl"
    assert ran.stdout.startswith("error: [Errno 27] File too large: ") and str(path) in ran.stdout
    rows = [json.loads(line) for line in path.read_text().splitlines()]  # every line whole
    assert len(rows) % 100 == 0 and len(rows) > 0  # cut at a flush
    assert [row["k"] for row in rows] == list(range(len(rows)))


def test_a_run_whose_record_cannot_be_written_stops_safely(tmp_path):
    """The same limit on a whole simulated run: the loop turns the recorder's error into a
    fault (a safe stop), and the tool says which file in one line."""
    code = textwrap.dedent("""
        import resource, signal, sys
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))
        from controller.cli.trial_cli import main
        sys.exit(main(sys.argv[1:]))
    """)
    out = tmp_path / "trial"
    ran = subprocess.run(
        [sys.executable, "-c", code, "--task", "usb_c", "--seed", "0", "--out", str(out),
         "--set", "touch_spiral.timeout_s=6.0"],
        capture_output=True, text=True, cwd=ROOT, timeout=300,
    )  # fmt: skip
    assert "Traceback" not in ran.stderr, ran.stderr
    summary = json.loads((out / "trial.json").read_text())
    assert summary["loop"]["reason"] == "fault"
    assert "File too large" in summary["loop"]["message"]
    assert str(out / "ticks.jsonl") in summary["loop"]["message"]
    assert summary["result"]["failure_reason"] == "device_fault"
    for line in (out / "ticks.jsonl").read_text().splitlines():
        json.loads(line)
