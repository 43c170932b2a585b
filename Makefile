# The two commands of the README. Both create .venv with the interpreter in $(PYTHON).
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
OUT ?= out

.PHONY: demo test clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[test]"
	touch $@ $(VENV)/.installed

## make demo: install, run the main job on the bundled default, figures in out/
demo: $(VENV)/.installed
	$(BIN)/servotune tune models/paper_x_axis --out $(OUT)/tune_paper_x_axis --force

## make test: install with the test extra, run the whole suite with doctests
test: $(VENV)/.installed-test
	$(BIN)/python -m pytest -q

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
