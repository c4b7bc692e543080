# Every target does its own set-up: a fresh machine needs only python3 (with venv) and make.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.s2r-installed

.PHONY: test demo lint typecheck pytest test-browser bench profiles calibration-sample clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[ros,dev,mujoco]"
	touch $(STAMP)

test: $(STAMP) lint typecheck pytest

lint: $(STAMP)
	$(BIN)/ruff check s2r tests bench

typecheck: $(STAMP)
	$(BIN)/mypy s2r

pytest: $(STAMP)
	$(BIN)/pytest -q -n 2 --dist loadfile

demo: $(STAMP)
	$(BIN)/python -m s2r.cli.demo

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache

test-browser: $(STAMP)
	@if [ ! -x /usr/bin/chromium ]; then apt-get update && apt-get install -y chromium; fi
	$(BIN)/pytest -q -m browser tests/validate

# The sample "recorded" calibration set of a simulated D435 unit (calibration/README.md).
calibration-sample: $(STAMP)
	$(BIN)/s2r render boards calibration/d435_unit_truth.yaml --views 24 --seed 7 --noise 2 \
		-o calibration/d435_unit_sample --force

# Rebuild profiles/sim/*.yaml from urdf/ (a test checks the shipped files match).
profiles: $(STAMP)
	$(BIN)/s2r profile regenerate-sim

# Speed and accuracy figures side by side with plain OpenCV (prints; never asserts times).
bench: $(STAMP)
	for script in bench/bench_*.py; do echo "== $$script"; $(BIN)/python $$script || exit 1; done
