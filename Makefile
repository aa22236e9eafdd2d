# The README's commands. `demo` and `test` install into .venv first when needed.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# make trials: the held-out report (docs/BENCHMARKS.md "Insertion trials" names its seeds
# before any run on them) of the product's controller, the oracle and the blind baseline, at
# the default insert speed, on every core; run it again to resume where it stopped
SEEDS       ?= 4000:4200
SPEEDS      ?= 0.004
CONTROLLERS ?= dipole,oracle,blind
WORKERS     ?= $(shell nproc 2>/dev/null || echo 2)

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
	@for task in usb_c usb_a; do \
	  resume=$$(test -f out/trials/$$task/comparison.json -o -d out/trials/$$task/cells && echo --resume); \
	  MPLBACKEND=Agg $(BIN)/python scripts/compare_trials.py --task $$task --controllers $(CONTROLLERS) \
	    --seeds $(SEEDS) --speeds $(SPEEDS) --workers $(WORKERS) --out out/trials/$$task $$resume \
	    || exit $$?; \
	done
	$(BIN)/python scripts/publish_trials.py out/trials --docs docs

lint: $(STAMP)
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache
