# The two set-up commands of the README. Each installs into .venv when needed.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test bench clean sysdeps lock

$(STAMP): pyproject.toml constraints.txt
	@test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c constraints.txt -e ".[dev]"
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

# Refresh constraints.txt from the newest versions pyproject.toml allows: a fresh venv,
# the install, then the frozen list. Run the tests before committing the new file.
lock:
	rm -rf .venv-lock && $(PY) -m venv .venv-lock
	.venv-lock/bin/python -m pip install --quiet --upgrade pip
	.venv-lock/bin/python -m pip install --quiet -e ".[dev]"
	{ echo "# Versions the test suite was last run with; 'make' installs with these as constraints."; \
	  echo "# Update deliberately: see docs/development.md (make lock)."; \
	  .venv-lock/bin/python -m pip freeze --exclude-editable; } > constraints.txt
	rm -rf .venv-lock
