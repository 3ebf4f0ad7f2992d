# The two commands of the README.  Both create .venv when missing and install fdikit into it.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin

.PHONY: demo test docs bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade pip

$(VENV)/.installed: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install -e .
	touch $@

$(VENV)/.installed-dev: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install -e ".[dev]"
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(BIN)/fdikit demo

test: $(VENV)/.installed-dev
	$(BIN)/ruff check src tests benchmarks tools docs/hooks
	$(BIN)/python -m pytest -q -p no:cacheprovider --doctest-modules src tests

$(VENV)/.installed-docs: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install -e ".[docs]"
	touch $@

# The documentation site (mkdocs-material + mkdocstrings) into site/; any warning fails the build.
docs: $(VENV)/.installed-docs
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

bench: $(VENV)/.installed-dev
	$(BIN)/python benchmarks/bench_simulate.py
	$(BIN)/python benchmarks/bench_vehicle.py
	$(BIN)/python benchmarks/bench_aircraft.py

clean:
	rm -rf $(VENV) out site .pytest_cache
