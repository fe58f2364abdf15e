# Two commands on a fresh machine: `make demo` and `make test`. Both build .venv from the pinned
# requirements the first time (and again when requirements or setup.py change).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: demo test venv bench clean

venv: $(STAMP)

$(STAMP): requirements.txt requirements-test.txt setup.py setup.cfg package.xml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements-test.txt
	$(BIN)/python -m pip install --quiet --no-deps --no-build-isolation -e .
	touch $(STAMP)

demo: $(STAMP)
	mkdir -p $(OUT)
	$(BIN)/fastep-sim case_study_1 --seed 0 --json $(OUT)/demo.json --plot $(OUT)/demo.png

test: $(STAMP)
	$(BIN)/python -m pytest -q tests

bench: $(STAMP)
	$(BIN)/python -m benchmarks.step_latency
	$(BIN)/python -m benchmarks.run_time
	$(BIN)/python -m benchmarks.path_length

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info
