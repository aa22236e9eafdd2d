"""The slip evaluation script runs on the gel model and writes its report (quick mode).

Its precision and recall are measured numbers, not asserted here; what is asserted are the
properties the detector must have on any run: negatives never flag slip and the re-zero
policy never recommends a re-zero while the grasp is loaded.
"""

import importlib.util
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load_script(monkeypatch):
    spec = importlib.util.spec_from_file_location("eval_slip", ROOT / "scripts" / "eval_slip.py")
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_quick_evaluation_reports_and_keeps_the_hard_properties(tmp_path, monkeypatch):
    script = load_script(monkeypatch)
    out = tmp_path / "SLIP.md"
    args = ["--quick", "--grips", "10", "--objects", "plate", "--out", str(out)]
    assert script.main(args) == 0
    text = out.read_text()
    assert "| 10 | plate |" in text and "| all | all |" in text
    assert "| 10 | plate | shear +x |" in text and "| 10 | plate | tilt x |" in text

    report = script.evaluate(grips_n=(10.0,), objects=("square_peg",), quick=True)
    overall = report["overall"]
    assert overall["frames"] == sum(row["frames"] for row in report["sequences"])
    assert overall["negative_false_alarm_rate"] == 0.0
    assert overall["rezero_under_load_frames"] == 0
    assert 0.0 <= overall["incipient"]["precision"] <= 1.0
    assert not math.isnan(overall["gross"]["recall"])
    positive = next(row for row in report["sequences"] if row["positive"])
    assert "incipient_delay" in positive and "gross_delay" in positive
