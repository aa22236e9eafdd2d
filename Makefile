# The README's commands. `demo` and `test` install into .venv first when needed.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# make trials: issue 24's report, on its held-out seeds (named before its run; a new machine
# gets new seeds, docs/BENCHMARKS.md "Insertion trials"), at the default insert speed
SEEDS  ?= 4000:4200
SPEEDS ?= 0.004

.PHONY: install demo estimator-demo test typecheck bench evaluate trials calibrations lint clean

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	rm -rf out/demo
	MPLBACKEND=Agg $(BIN)/python scripts/run_trial.py --task usb_c --seed 0 --out out/demo

estimator-demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python scripts/demo.py --out out/estimator-demo

test: $(STAMP)
	MPLBACKEND=Agg SDL_VIDEODRIVER=dummy $(BIN)/python -m pytest

typecheck: $(STAMP)
	$(BIN)/mypy

bench: $(STAMP)
	$(BIN)/python scripts/bench_estimation.py --write docs/BENCHMARKS.md

evaluate: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python scripts/evaluate.py --docs docs --work out/evaluate

calibrations: $(STAMP)
	$(BIN)/python scripts/calibrate_task.py --task usb_c --out configs/calibrations/usb_c.yaml
	$(BIN)/python scripts/calibrate_task.py --task usb_a --out configs/calibrations/usb_a.yaml

trials: $(STAMP)
	rm -rf out/trials
	MPLBACKEND=Agg $(BIN)/python scripts/compare_trials.py --task usb_c --seeds $(SEEDS) --speeds $(SPEEDS) --workers 2 --out out/trials/usb_c
	MPLBACKEND=Agg $(BIN)/python scripts/compare_trials.py --task usb_a --seeds $(SEEDS) --speeds $(SPEEDS) --workers 2 --out out/trials/usb_a
	$(BIN)/python scripts/publish_trials.py out/trials --docs docs

lint: $(STAMP)
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache
