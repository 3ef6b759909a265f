# Set-up and everyday commands. Only this file and pyproject.toml install things.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CORE_STAMP := $(VENV)/.installed-core
DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: install run test lint schemas docs fuzz wheel-check samples bench bench-quick train-detector eval eval-real eval-construction clean sample-bag profiles

install: $(STAMP)

# The package alone (what `make run` needs): no extra. --no-compile: Python byte-compiles the modules
# a command imports when it first runs them, not every module of every dependency at install time.
$(CORE_STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet --no-compile -e .
	touch $(CORE_STAMP)

# Every extra the tests and the other targets need: [test] (pytest, ruff, mypy), [train] (torch, the
# detector's training), [ros] (roslibpy, the live link), [cluster] (Ray), [fast] (numba), [detector]
# (onnxruntime).
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test,train,ros,cluster,fast,detector]"
	touch $(STAMP)

run: $(CORE_STAMP)
	$(BIN)/bim-extract sample_models/block_a.ifc -o runs/block_a_site
	$(BIN)/bim-init run --config sample_models/block_a.site.yaml --site runs/block_a_site --out runs/block_a_session

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

# The docs site into site/, strict: a broken link, anchor or cross-reference fails (mkdocs.yml).
# (The two variables silence banners about MkDocs 2.0 and Material's end of life; pyproject pins mkdocs<2.)
docs: $(DOCS_STAMP)
	DISABLE_MKDOCS_2_WARNING=true NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --clean

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	touch $(DOCS_STAMP)

# The site config's JSON Schema, generated from the settings records (a test fails when it is stale).
schemas: install
	$(BIN)/python -m initcli.config --write

# The shipped model's detector profiles (sim.detector.profile: default-real, default-renders), measured
# again with bim-init detector calibrate (a test fails when default.onnx changes and they do not): on
# the hold-out of the DoorDetect photos (20 % by sha1 of the file name; never the training part) and
# on 500 renders of block_b, a layout the model was not trained on (about a minute on 2 cores).
DOORDETECT ?= ../shared/datasets/doordetect_train
PROFILES := runs/profiles
profiles: install
	rm -rf $(PROFILES) && mkdir -p $(PROFILES)
	printf 'names: [door, lift, stairs]\nval:\n  - {path: %s, classes: {0: door}, holdout: 0.2, part: holdout}\n' \
		"$(abspath $(DOORDETECT))" > $(PROFILES)/doordetect_holdout.yaml
	$(BIN)/bim-extract sample_models/block_b.ifc -o $(PROFILES)/block_b_site
	$(BIN)/bim-init detector synth --site $(PROFILES)/block_b_site --out $(PROFILES)/block_b_renders \
		--images 500 --seed 7 --val-fraction 1.0
	$(BIN)/bim-init detector calibrate default --data $(PROFILES)/doordetect_holdout.yaml \
		-o initcli/detector/models/default.real.profile.json
	$(BIN)/bim-init detector calibrate default --data $(PROFILES)/block_b_renders/data.yaml \
		-o initcli/detector/models/default.renders.profile.json

# Every file reader fed mutated and random files for FUZZ_SECONDS each (17 readers: about 2 minutes);
# an input that gives anything but the file read or one InputError line fails (tests/fuzz/targets.py).
FUZZ_SECONDS ?= 6
fuzz: install
	$(BIN)/python -m tests.fuzz.run --seconds $(FUZZ_SECONDS)

# Build the wheel, install it into a fresh venv outside the source tree and run both commands there.
wheel-check: install
	PYTHON=$(BIN)/python .ci/wheel_smoke.sh

samples: install
	$(BIN)/python -m bimtools.samples --out sample_models

# Every benchmark, benchmarks/bench_NAME.py (tests/benchmarks checks that this names them all).
BENCHMARKS := bag2log claims detector eval extract lidar_twins match matcher_scale offline_match raycast real_lidar registration_scale session survey watch

# Each benchmark whole (bench_claims alone takes about 40 min on 2 cores; bench_extract also
# measures the real models in ../shared/ifc where that folder is).
bench: install
	@set -e; for b in $(BENCHMARKS); do \
		echo "== bench_$$b"; start=$$(date +%s); \
		$(BIN)/python benchmarks/bench_$$b.py; \
		echo "== bench_$$b: $$(( $$(date +%s) - start )) s"; \
	done

# Each benchmark's smoke run on the samples (what CI runs: a few minutes in all on 2 cores). A
# crash fails it; a slow number does not.
bench-quick: install
	@set -e; for b in $(BENCHMARKS); do \
		echo "== bench_$$b --quick"; start=$$(date +%s); \
		$(BIN)/python benchmarks/bench_$$b.py --quick; \
		echo "== bench_$$b --quick: $$(( $$(date +%s) - start )) s"; \
	done

# Train the shipped detector's recipe (initcli/detector/models/default.md) from scratch: a GPU when
# torch sees one; ARGS=--smoke checks every step in a few minutes on CPU.
train-detector: install
	BIN=$(BIN) scripts/train_detector.sh $(ARGS)

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
	rm -rf $(VENV) runs *_site .pytest_cache eval_results eval_real eval_construction site
