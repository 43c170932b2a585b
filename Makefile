# The two commands of the README. Both create .venv with the interpreter in $(PYTHON).
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
OUT ?= out

# root installs system packages directly, anyone else through sudo
SUDO ?= $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: demo test clean browser

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
## (the command exits 1 when the design is not verified: a verdict, not a failure of the demo)
demo: $(VENV)/.installed
	$(BIN)/servotune tune models/paper_x_axis --out $(OUT); status=$$?; \
	if [ $$status -gt 1 ]; then exit $$status; fi

## headless Chromium and its driver for the browser test of the report (Debian packages);
## installed only when one of them is missing
browser:
	@if command -v chromium >/dev/null 2>&1 && command -v chromedriver >/dev/null 2>&1; then \
		:; \
	else \
		$(SUDO) apt-get update && \
		DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y chromium chromium-driver; \
	fi

## make test: install with the test extra, run the whole suite with doctests
test: $(VENV)/.installed-test browser
	$(BIN)/python -m pytest -q

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache
