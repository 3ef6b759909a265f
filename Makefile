# Set-up and everyday commands. Only this file and pyproject.toml install things.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install run test lint fuzz wheel-check samples bench eval eval-real eval-construction clean sample-bag

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,train,ros,cluster]"
	touch $(STAMP)

run: install
	$(BIN)/bim-extract sample_models/block_a.ifc -o runs/block_a_site
	$(BIN)/bim-init run --config sample_models/block_a.site.yaml --out runs/block_a_session

# The sample bag a user tries first: a simulated session on block_a as a ROS 2 MCAP (opens in Foxglove).
sample-bag: install
	$(BIN)/bim-init run --config sample_models/block_a.site.yaml --out runs/sample_bag_session \
		--start 10.0,11.0,0 --seed 3 --quiet --record runs/block_a_session.mcap
	$(BIN)/bim-init bag2log runs/block_a_session.mcap -o runs/block_a_session.from_bag.jsonl

test: install
	$(BIN)/python -m pytest -q

lint: install
	$(BIN)/ruff check bimkit bimtools initcli tests benchmarks
	$(BIN)/ruff format --check bimkit bimtools initcli tests benchmarks
	$(BIN)/mypy

# Every file reader fed mutated and random files for FUZZ_SECONDS each (14 readers: under 2 minutes);
# an input that gives anything but the file read or one InputError line fails (tests/fuzz/targets.py).
FUZZ_SECONDS ?= 6
fuzz: install
	$(BIN)/python -m tests.fuzz.run --seconds $(FUZZ_SECONDS)

# Build the wheel, install it into a fresh venv outside the source tree and run both commands there.
wheel-check: install
	PYTHON=$(BIN)/python .ci/wheel_smoke.sh

samples: install
	$(BIN)/python -m bimtools.samples --out sample_models

bench: install
	$(BIN)/python benchmarks/bench_extract.py ../shared/ifc/*.ifc sample_models/*.ifc
	$(BIN)/python benchmarks/bench_match.py --quick
	$(BIN)/python benchmarks/bench_session.py --starts 20
	$(BIN)/python benchmarks/bench_raycast.py
	$(BIN)/python benchmarks/bench_eval.py --starts 10

# The paper's Tables 2 and 3 on the three samples: 100 starts x 4 methods each (about 10 min on 2 cores).
eval: install
	$(BIN)/bim-init eval --config sample_models/eval.yaml --out eval_results --resume

# Every storey with 8 or more features of the real IFC models in ../shared/ifc (10 starts x 4 methods each).
eval-real: install
	$(BIN)/bim-init eval --config sample_models/eval_real.yaml --out eval_real --resume

# The same samples under the construction reality profile (the site as built, sim.reality: construction).
eval-construction: install
	$(BIN)/bim-init eval --config sample_models/eval.yaml --reality construction --out eval_construction --resume

clean:
	rm -rf $(VENV) runs *_site .pytest_cache eval_results eval_real eval_construction
