# Every target bootstraps .venv itself: a fresh machine needs only Python 3.11 and make.
PYTHON ?= $(shell command -v python3.11 2>/dev/null || command -v python3)
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

.PHONY: run test test-all bench lint docs clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	$(PY) -m stiffknots.studies.warmup  # compile the numba kernels once
	touch $(STAMP)

run: $(STAMP)  ## the main job on a small default budget
	$(VENV)/bin/stiffknots paper --budget small --out results/paper --overwrite

test: $(STAMP)  ## the default (fast) test suite on both cores; pytest exit 5 (no tests) fails
	$(PY) -m pytest -m "not slow" -q -n 2

test-all: $(STAMP)  ## every test, slow ones included
	$(PY) -m pytest -q

bench: $(STAMP)  ## benchmarks that print numbers (see docs/benchmarks.md)
	$(PY) bench/run_bench.py

lint: $(STAMP)  ## ruff, and the layer contracts of pyproject.toml (import-linter)
	$(VENV)/bin/ruff check src tests bench scripts
	$(VENV)/bin/lint-imports

# The site → docs/_build/html: cli.md and benchmarks.md regenerated from the commands and the
# benchmarks' JSON, the relative links of README.md and the pages checked, then Sphinx with
# warnings as errors (nitpicky); no network (no intersphinx, no external link check).
docs: $(STAMP)  ## the documentation site (docs/_build/html/index.html)
	$(PY) scripts/docs_cli.py docs/cli.md
	$(PY) bench/make_page.py docs/benchmarks.md
	$(PY) scripts/check_links.py README.md docs
	rm -rf docs/api  # the API stubs are regenerated: none left of a renamed module
	$(PY) -m sphinx -W --keep-going -n -q -b html docs docs/_build/html

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info docs/_build docs/api
