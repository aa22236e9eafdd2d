# The README's commands. `demo` and `test` install into .venv first when needed.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# make trials: the held-out report (docs/BENCHMARKS.md "Held-out seed ranges" names its seeds
# before any run on them) of the product's controller, the oracle and the blind baseline, at
# the default insert speed, on every core; run it again to resume where it stopped
SEEDS       ?= 10600:10800
SPEEDS      ?= 0.004
CONTROLLERS ?= dipole,oracle,blind
WORKERS     ?= $(shell nproc 2>/dev/null || echo 2)

# make check-lerobot (not part of `make test`): the real lerobot, pinned, in its own Python 3.12
# environment, loads an export of two episodes of different tasks and checks every frame
# (evaluation/episodes/lerobot_check.py; docs/EPISODES.md "Checked with LeRobot itself")
LEROBOT_VERSION := 0.6.1
PYTHON312 := $(shell command -v python3.12 >/dev/null && python3.12 -c '' 2>/dev/null \
               && command -v python3.12 || ls -d $$(pyenv root 2>/dev/null)/versions/3.12*/bin/python3.12 2>/dev/null | tail -1)
LEROBOT_VENV  := .venv-lerobot
LEROBOT_STAMP := $(LEROBOT_VENV)/.installed-$(LEROBOT_VERSION)
CHECK_OUT     := out/check-lerobot

.PHONY: install demo estimator-demo test typecheck bench evaluate trials calibrations lint clean check-lerobot

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	rm -rf out/demo
	MPLBACKEND=Agg $(BIN)/tactile trial --task usb_c --seed 0 --out out/demo

estimator-demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m evaluation demo --out out/estimator-demo

# PYTHONDONTWRITEBYTECODE= : the suite keeps its bytecode (__pycache__) even where the
# environment turns it off; a run after the first then skips pytest's assertion rewriting
# (about 6 s of CPU per worker) and the compiling in each of its processes
test: $(STAMP)
	MPLBACKEND=Agg SDL_VIDEODRIVER=dummy PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest

typecheck: $(STAMP)
	$(BIN)/mypy

bench: $(STAMP)
	$(BIN)/python -m evaluation bench_estimation --write docs/BENCHMARKS.md

evaluate: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m evaluation evaluate --docs docs --work out/evaluate

calibrations: $(STAMP)
	$(BIN)/python -m evaluation calibrate_task --task usb_c --out configs/calibrations/usb_c.yaml
	$(BIN)/python -m evaluation calibrate_task --task usb_a --out configs/calibrations/usb_a.yaml

trials: $(STAMP)
	@for task in usb_c usb_a; do \
	  resume=$$(test -f out/trials/$$task/comparison.json -o -d out/trials/$$task/cells && echo --resume); \
	  MPLBACKEND=Agg $(BIN)/tactile compare --task $$task --controllers $(CONTROLLERS) \
	    --seeds $(SEEDS) --speeds $(SPEEDS) --workers $(WORKERS) --out out/trials/$$task $$resume \
	    || exit $$?; \
	done
	$(BIN)/python -m evaluation publish_trials out/trials --docs docs

lint: $(STAMP)
	$(BIN)/ruff check .

$(LEROBOT_STAMP):
	@test -n "$(PYTHON312)" || { echo "check-lerobot: Python 3.12 not found; set PYTHON312=/path/to/python3.12" >&2; exit 2; }
	$(PYTHON312) -m venv $(LEROBOT_VENV)
	$(LEROBOT_VENV)/bin/python -m pip install --quiet "lerobot[dataset]==$(LEROBOT_VERSION)"
	touch $(LEROBOT_STAMP)

check-lerobot: $(STAMP) $(LEROBOT_STAMP)
	rm -rf $(CHECK_OUT)
	@for task in usb_c usb_a; do \
	  MPLBACKEND=Agg $(BIN)/tactile trial --task $$task --seed 0 --out $(CHECK_OUT)/$$task > /dev/null || exit $$?; \
	done
	$(BIN)/tactile replay export $(CHECK_OUT)/usb_c/episode.mcap $(CHECK_OUT)/usb_a/episode.mcap \
	  --lerobot $(CHECK_OUT)/dataset
	@frames() { $(BIN)/tactile replay summary $(CHECK_OUT)/$$1/episode.mcap \
	            | awk '$$1 == "/tactile/image" {print $$2}'; }; \
	set -x; PYTHONPATH=$(CURDIR) $(LEROBOT_VENV)/bin/python -m evaluation check_lerobot $(CHECK_OUT)/dataset \
	  --episode "insert the usb_c plug=$$(frames usb_c)" --episode "insert the usb_a plug=$$(frames usb_a)"

clean:
	rm -rf $(VENV) $(LEROBOT_VENV) out .pytest_cache
