# Two commands on a fresh machine: `make demo` and `make test`. Both build .venv from the pinned
# requirements the first time (and again when requirements or setup.py change).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: demo test fuzz venv bench clean

venv: $(STAMP)

$(STAMP): requirements.txt requirements-test.txt setup.py setup.cfg package.xml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements-test.txt
	$(BIN)/python -m pip install --quiet --no-deps --no-build-isolation -e .
	touch $(STAMP)

# The two-robot case study on the live ROS 2 graph (separate node processes over DDS, simulated clock).
demo: $(STAMP)
	mkdir -p $(OUT)
	ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST $(BIN)/fastep-launch case_study_1 --rtf 50 --seed 0 \
		--record $(OUT)/demo.mcap --json $(OUT)/demo.json --plot $(OUT)/demo.png
	$(BIN)/fastep-report $(OUT)/demo.mcap --out $(OUT)/demo_report

# Two workers: the tests on a live ROS graph run one after another on one of them, the rest spread over both
# (tests/conftest.py says why). TEST_WORKERS=0 runs everything in this process, in file order.
TEST_WORKERS ?= 2
test: $(STAMP)
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadgroup tests

# The property tests with fresh random examples, ROUNDS times (make test always tries the same ones).
ROUNDS ?= 20
fuzz: $(STAMP)
	for i in $$(seq $(ROUNDS)); do HYPOTHESIS_PROFILE=explore $(BIN)/python -m pytest -q -x \
		tests/fastep_core/test_properties.py tests/fastep_core/planning/test_optimal.py || exit 1; done

# Measurements run by hand (minutes, not seconds); results and commands are in docs/benchmarks.md.
bench: $(STAMP)
	$(BIN)/python -m benchmarks.step_latency
	$(BIN)/python -m benchmarks.run_time
	$(BIN)/python -m benchmarks.path_length
	$(BIN)/fastep-bench --runs 30 --out docs/
	$(BIN)/python -m benchmarks.graph_latency
	$(BIN)/python -m benchmarks.graph_scaling
	$(BIN)/python -m benchmarks.soak --scenarios 500
	$(BIN)/python -m benchmarks.trap_escape --scenarios 60

clean:
	rm -rf $(VENV) $(OUT) build *.egg-info
