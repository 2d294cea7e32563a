# Two entry points: `make demo` (main job on shipped defaults) and `make test`.
# Both install what they need and can run twice: `make demo` Debian's libosmesa6, a
# .venv and ledsim without torch (running observers needs none), and compiles the control
# step's kernels once (numba); `make test` also CPU PyTorch (training), the dev tools and
# every optional extra the tests use.
PY      ?= python3
VENV    := .venv
BIN     := $(VENV)/bin
STAMP   := $(VENV)/.installed-run
STAMP_ALL := $(VENV)/.installed-all
OUT     ?= out/demo
# A path in a .pth, not setuptools' import hook: Python starts in 3 ms, not 25 ms (the hook
# imports pathlib and re), which shortens the moment where Ctrl-C meets Python's own start.
EDITABLE := --config-settings editable_mode=compat
# PyTorch's CPU wheels; where that index cannot be reached, pip's default one.
TORCH_INDEX ?= https://download.pytorch.org/whl/cpu

.PHONY: demo test bench lint tables clean

$(STAMP): pyproject.toml
	@bash scripts/install_system_deps.sh
	@test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/pip install -q -e . $(EDITABLE)
	MUJOCO_GL=osmesa $(BIN)/python -m ledsim.loop.warm
	@touch $(STAMP)

$(STAMP_ALL): $(STAMP)
	$(BIN)/pip install -q --timeout 10 --retries 0 --index-url $(TORCH_INDEX) torch==2.13.0 \
		|| $(BIN)/pip install -q torch==2.13.0
	$(BIN)/pip install -q -e '.[dev,ray,onnx,train,rl]' $(EDITABLE)
	@touch $(STAMP_ALL)

demo: $(STAMP)
	MUJOCO_GL=osmesa $(BIN)/ledsim demo --out $(OUT)

test: $(STAMP_ALL)
	$(BIN)/ruff check ledsim observer tests scripts
	MUJOCO_GL=osmesa $(BIN)/python -m pytest

bench: $(STAMP_ALL)
	MUJOCO_GL=osmesa $(BIN)/python scripts/bench.py

lint: $(STAMP_ALL)
	$(BIN)/ruff check ledsim observer tests scripts

tables: $(STAMP_ALL)
	$(BIN)/python scripts/tables.py table1
	$(BIN)/python scripts/tables.py table2

clean:
	rm -rf $(VENV) out *.egg-info
