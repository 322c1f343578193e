# Two entry points for a fresh machine: `make run` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
REPORT ?= report

.PHONY: run test install install-test install-docs docs bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet -e ".[test,docs]"
	touch $@ $(VENV)/.installed $(VENV)/.installed-docs

$(VENV)/.installed-docs: pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet -e ".[docs]"
	touch $@ $(VENV)/.installed

install: $(VENV)/.installed
install-test: $(VENV)/.installed-test
install-docs: $(VENV)/.installed-docs

run: install
	$(BIN)/srdda paper all --method all --report $(REPORT)

test: install-test
	$(BIN)/mypy
	$(MAKE) docs
	$(BIN)/python -m pytest -q

# The manual (mkdocs.yml) into site/, every warning an error: broken links, docstrings mkdocstrings cannot
# read, pages missing from the nav. The two variables silence banners the theme and a plugin print.
docs: install-docs
	NO_MKDOCS_2_WARNING=1 DISABLE_MKDOCS_2_WARNING=true $(BIN)/mkdocs build --strict --quiet

bench: install-test
	$(BIN)/python benchmarks/run_benchmarks.py

clean:
	rm -rf $(VENV) $(REPORT) build site *.egg-info src/*.egg-info
