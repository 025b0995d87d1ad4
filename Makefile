# Two commands on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

.PHONY: demo test test-fast bench lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/odomkit demo --out demo-output --force

# The whole suite, then the linters (ruff, mypy): CI runs exactly this.
test: $(STAMP)
	$(BIN)/python -m pytest src tests
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy src

test-fast: $(STAMP)
	$(BIN)/python -m pytest src tests -m "not slow"

bench: $(STAMP)
	$(BIN)/python benchmarks/dead_reckoning.py
	$(BIN)/python benchmarks/propagation.py
	$(BIN)/python benchmarks/montecarlo.py

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy src

clean:
	rm -rf $(VENV) demo-output .pytest_cache
