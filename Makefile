# Two entry points: `make demo` (main job on shipped defaults) and `make test`.
# Both install what they need (Debian's libosmesa6, a .venv, CPU torch) and can run twice.
PY      ?= python3
VENV    := .venv
BIN     := $(VENV)/bin
STAMP   := $(VENV)/.installed
OUT     ?= out/demo

.PHONY: demo test bench lint tables clean

$(STAMP): pyproject.toml
	@bash scripts/install_system_deps.sh
	@test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/pip install -q torch==2.13.0
	$(BIN)/pip install -q -e '.[dev,ray]'
	@touch $(STAMP)

demo: $(STAMP)
	MUJOCO_GL=osmesa $(BIN)/ledsim demo --out $(OUT)

test: $(STAMP)
	$(BIN)/ruff check ledsim observer tests scripts
	MUJOCO_GL=osmesa $(BIN)/python -m pytest

bench: $(STAMP)
	MUJOCO_GL=osmesa $(BIN)/python scripts/bench.py

lint: $(STAMP)
	$(BIN)/ruff check ledsim observer tests scripts

tables: $(STAMP)
	$(BIN)/python scripts/tables.py table1
	$(BIN)/python scripts/tables.py table2

clean:
	rm -rf $(VENV) out *.egg-info
