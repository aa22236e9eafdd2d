# The README's commands. `demo` and `test` install into .venv first when needed.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: install demo test bench evaluate lint clean

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python scripts/demo.py --out out/demo

test: $(STAMP)
	MPLBACKEND=Agg SDL_VIDEODRIVER=dummy $(BIN)/python -m pytest

bench: $(STAMP)
	$(BIN)/python scripts/bench_estimation.py --write docs/BENCHMARKS.md

evaluate: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python scripts/evaluate.py --docs docs --work out/evaluate

lint: $(STAMP)
	$(BIN)/ruff check .

clean:
	rm -rf $(VENV) out .pytest_cache
