# The two set-up commands of the README. Each installs into .venv when needed.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean sysdeps

$(STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	@touch $(STAMP)

# Debian packages some features need (Graphviz, Chromium, ARM compiler, QEMU): installed
# when root, otherwise a note; see tools/sysdeps.sh.
sysdeps:
	@tools/sysdeps.sh

demo: $(STAMP) sysdeps
	$(BIN)/mechatron demo --out demo_output

test: $(STAMP) sysdeps
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python bench/run_all.py

clean:
	rm -rf $(VENV) demo_output .pytest_cache
