# Two commands on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

.PHONY: demo test test-fast test-browser docs bench lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/odomkit demo --out demo-output --force

# The whole suite, then the linters (ruff, mypy): CI runs exactly this. The tests run in one
# pytest-xdist worker per core (`-n auto`; PYTEST_XDIST_AUTO_NUM_WORKERS=N sets how many),
# each test file in one worker, so that a module's fixtures are built once; `pytest FILE`
# by hand stays serial.
PYTEST_PARALLEL := -n auto --dist loadfile
test: $(STAMP)
	$(BIN)/python -m pytest $(PYTEST_PARALLEL) src tests
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy src

test-fast: $(STAMP)
	$(BIN)/python -m pytest $(PYTEST_PARALLEL) src tests -m "not slow"

# The HTML report in a real browser: Chromium and its driver from Debian's packages
# (installed when missing, as root or through sudo), the `browser` extra (selenium), then
# the browser tests, which save a screenshot (ODOMKIT_SCREENSHOT=path.png keeps one).
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
test-browser: $(STAMP)
	@command -v chromium >/dev/null && command -v chromedriver >/dev/null || \
	  { $(SUDO) apt-get update && $(SUDO) apt-get install -y chromium chromium-driver; }
	@$(BIN)/python -c "import selenium" 2>/dev/null || $(BIN)/python -m pip install --quiet -e ".[test,browser]"
	$(BIN)/python -m pytest tests/browser -m browser -v

# The documentation site (mkdocs.yml, docs/) into site/, warnings as errors.
docs: $(STAMP)
	@$(BIN)/python -c "import mkdocstrings_handlers.python, material" 2>/dev/null || \
	  $(BIN)/python -m pip install --quiet -e ".[docs]"
	NO_MKDOCS_2_WARNING=1 $(BIN)/python -m mkdocs build --strict --site-dir site

bench: $(STAMP)
	$(BIN)/python benchmarks/dead_reckoning.py
	$(BIN)/python benchmarks/propagation.py
	$(BIN)/python benchmarks/montecarlo.py

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy src

clean:
	rm -rf $(VENV) demo-output .pytest_cache site
