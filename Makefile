# The two commands of the README. Each builds its own virtual environment.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.navlib-installed

.PHONY: report test test-browser docs lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

report: $(STAMP)
	$(PY) -m navlib report

test: $(STAMP)
	$(PY) -m ruff check navlib tests benchmarks
	$(PY) tests/docstring_coverage.py
	$(PY) -m pytest -n 2 -q --durations=10

# API reference (Sphinx + numpydoc + myst-parser from the [docs] extra): docs/api/conf.py,
# pages generated afresh from the docstrings, warnings are errors. Output: build/docs/.
DOCS_STAMP := $(VENV)/.navlib-docs-installed

$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e ".[dev,docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	rm -rf docs/api/generated build/docs
	$(PY) -m sphinx -W --keep-going -q -c docs/api docs build/docs
	printf '<meta http-equiv="refresh" content="0; url=api/index.html">\n' > build/docs/index.html

# Browser tests: JupyterLab + Debian's chromium (installed with apt-get when missing: CI runs
# as root), Playwright from the [browser] extra. Not part of `make test`.
CHROMIUM ?= /usr/bin/chromium
BROWSER_STAMP := $(VENV)/.navlib-browser-installed

$(BROWSER_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e ".[dev,browser]"
	touch $(BROWSER_STAMP)

test-browser: $(BROWSER_STAMP)
	@test -x $(CHROMIUM) || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; }
	$(PY) -m pytest -m browser -v tests/browser

bench: $(STAMP)
	$(PY) benchmarks/run.py

clean:
	rm -rf $(VENV) reports/*.html reports/*.ipynb build/docs docs/api/generated
