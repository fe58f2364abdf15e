# Two commands on a fresh machine: `make demo` and `make test`. Both build .venv from the pinned
# requirements the first time (and again when requirements or setup.py change).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: demo test lint lint-counts fuzz venv bench clean docs

venv: $(STAMP)

# nav2_msgs and tf2_msgs are built from their definitions (interfaces/build.sh): the registry has no wheel of them.
$(STAMP): requirements.txt requirements-test.txt setup.py setup.cfg package.xml $(wildcard interfaces/*/* interfaces/*/*/* interfaces/*.*)
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements-test.txt
	$(BIN)/python -m pip install --quiet --no-build-isolation -e '.[ros-wheels,test]'
	sh interfaces/build.sh $(VENV)
	touch $(STAMP)

# The two-robot case study on the live ROS 2 graph (separate node processes over DDS, simulated clock).
demo: $(STAMP)
	mkdir -p $(OUT)
	ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST $(BIN)/fastep-launch case_study_1 --algorithm fastep --rtf 50 --seed 0 \
		--record $(OUT)/demo.mcap --json $(OUT)/demo.json --plot $(OUT)/demo.png
	$(BIN)/fastep-report $(OUT)/demo.mcap --out $(OUT)/demo_report

# The documentation site in out/site: the reference pages generated from the code, then MkDocs with every warning
# an error (mkdocs.yml). make test checks that the committed pages are current and that the site builds.
docs: $(STAMP)
	$(BIN)/python -m fastep_ros.reference docs/reference config/fastep.yaml
	$(BIN)/mkdocs build --strict

# Linter and type checker first (ruff.toml; [mypy] in setup.cfg), so a lint or type error fails make test.
# Then three workers: the tests on a live ROS graph in two units, each run one after another on one of them, the
# rest spread over all three (tests/conftest.py says why). TEST_WORKERS=0 runs everything in this process.
TEST_WORKERS ?= 3
test: $(STAMP) lint
	$(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadgroup tests

# A `# type: ignore` names its error code and says why after it: `# type: ignore[code]  # why`.
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m mypy
	@! grep -rnE --include='*.py' '# type: ignore(\[[^]]*\])? *$$' fastep_core msg_tools fastep_ros fastep_testing tests benchmarks \
		|| { echo 'each type: ignore above needs a reason: # type: ignore[code]  # why'; false; }

# Lint and type errors per file (mypy on tests and benchmarks too, which make lint does not type-check yet).
lint-counts: $(STAMP)
	@echo '== ruff check'; $(BIN)/ruff check --output-format concise --quiet . | cut -d: -f1 | sort | uniq -c | sort -rn
	@echo '== mypy'; $(BIN)/python -m mypy | grep ': error:' | cut -d: -f1 | sort | uniq -c | sort -rn
	@echo '== mypy tests benchmarks (bodies checked, annotations not required)'; \
		$(BIN)/python -m mypy --allow-untyped-defs --allow-incomplete-defs tests benchmarks \
		| grep -E '^(tests|benchmarks)/.*: error:' | cut -d: -f1 | sort | uniq -c | sort -rn
	@echo '== type: ignore without a reason'; grep -rnE --include='*.py' '# type: ignore(\[[^]]*\])? *$$' \
		fastep_core msg_tools fastep_ros fastep_testing tests benchmarks | cut -d: -f1 | sort | uniq -c | sort -rn

# The property tests with fresh random examples, ROUNDS times (make test always tries the same ones).
ROUNDS ?= 20
fuzz: $(STAMP)
	for i in $$(seq $(ROUNDS)); do HYPOTHESIS_PROFILE=explore $(BIN)/python -m pytest -q -x \
		tests/fastep_core/test_properties.py tests/fastep_core/planning/shortest_path/test_optimal.py || exit 1; done

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
	rm -rf $(VENV) $(OUT) build *.egg-info .mypy_cache .ruff_cache
