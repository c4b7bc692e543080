# Every target does its own set-up: a fresh machine needs only python3 (with venv) and make.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.s2r-installed
BYTECODE := $(VENV)/.s2r-bytecode

.PHONY: lock test librealsense-deps demo lint typecheck pytest test-browser test-recordings test-ros bench profiles calibration-sample clean

# Installs the tested versions: requirements.lock pins every package (pyproject.toml keeps ranges for users who
# `pip install s2r`). `make lock` refreshes it from today's releases; commit it only after `make test` is green.
LOCK := requirements.lock
EXTRAS := ros,dev,mujoco

$(STAMP): pyproject.toml $(LOCK)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet -c $(LOCK) --upgrade pip
	$(BIN)/python -m pip install --quiet -c $(LOCK) -e ".[$(EXTRAS)]"
	touch $(STAMP)

lock:
	rm -rf .lock-venv
	$(PYTHON) -m venv .lock-venv
	.lock-venv/bin/python -m pip install --quiet --upgrade pip
	.lock-venv/bin/python -m pip install --quiet ".[$(EXTRAS)]"
	{ echo "# The tested versions: make installs with these as constraints (pip install -c $(LOCK))."; \
	  echo "# Written by \`make lock\` ($$(date -u +%F), $$(.lock-venv/bin/python --version), $$(uname -m)); pyproject.toml keeps ranges."; \
	  echo "pip==$$(.lock-venv/bin/python -m pip --version | cut -d' ' -f2)"; \
	  .lock-venv/bin/python -m pip freeze --exclude s2r | grep -v '^#' | LC_ALL=C sort -f; } > $(LOCK).new
	mv $(LOCK).new $(LOCK)
	rm -rf .lock-venv

# s2r's modules compiled once (an editable install never compiles them, and with PYTHONDONTWRITEBYTECODE set
# every run would compile about 150 modules again: ~0.1 s of each `s2r` command). Redone when a source changes.
$(BYTECODE): $(STAMP) $(shell find s2r -name '*.py')
	$(BIN)/python -m compileall -q s2r
	touch $(BYTECODE)

test: $(STAMP) $(BYTECODE) librealsense-deps lint typecheck pytest

# pyrealsense2 (it writes the RealSense .db3 test recordings) loads libusb-1.0 at import; without it those tests skip.
librealsense-deps:
	@dpkg -s libusb-1.0-0 >/dev/null 2>&1 || (apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y \
		--no-install-recommends libusb-1.0-0) || echo "libusb-1.0-0 not installed: the pyrealsense2 tests will skip"

lint: $(STAMP)
	$(BIN)/ruff check s2r tests bench

typecheck: $(STAMP)
	$(BIN)/mypy s2r

pytest: $(STAMP) $(BYTECODE)
	$(BIN)/pytest -q -n 2 --dist loadfile

demo: $(STAMP) $(BYTECODE)
	$(BIN)/python -m s2r.cli.demo

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache

test-browser: $(STAMP)
	@if [ ! -x /usr/bin/chromium ]; then apt-get update && apt-get install -y chromium; fi
	$(BIN)/pytest -q -m browser tests/validate

# The recording inputs with H.264 videos: Debian's ffmpeg makes the test files (installed when missing, as root);
# without it those tests skip with the reason in `make pytest`.
test-recordings: $(STAMP) $(BYTECODE)
	@if ! command -v ffmpeg >/dev/null; then apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y \
		--no-install-recommends ffmpeg; fi
	$(BIN)/pytest -q -n 0 tests/recordings

# ROS's own consumers (Debian's ROS 1) on s2r's outputs, on a loopback-only roscore: installs what is missing (as
# root), then runs the tests marked ros. The -dev packages and libnodeletlib-tools carry the nodelet plugin
# descriptions and nodelet's package.xml that stereo_image_proc needs to load.
ROS_DEBS := ros-core ros-image-proc ros-stereo-image-proc libimage-proc-dev libstereo-image-proc-dev \
	libnodeletlib-tools python3-image-geometry python3-camera-calibration-parsers python3-rosbag python3-stereo-msgs python3-tf2-msgs \
	python3-tf2-ros
test-ros: $(STAMP)
	@missing=$$(for deb in $(ROS_DEBS); do dpkg -s $$deb >/dev/null 2>&1 || echo $$deb; done); \
	if [ -n "$$missing" ]; then apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y \
		--no-install-recommends $$missing; fi
	$(BIN)/pytest -q -n 0 -m ros tests/ros

# The sample "recorded" calibration set of a simulated D435 unit (calibration/README.md).
calibration-sample: $(STAMP)
	$(BIN)/s2r render boards calibration/d435_unit_truth.yaml --views 24 --seed 7 --noise 2 \
		-o calibration/d435_unit_sample --force

# Rebuild profiles/sim/*.yaml from urdf/ (a test checks the shipped files match).
profiles: $(STAMP)
	$(BIN)/s2r profile regenerate-sim

# Speed and accuracy figures side by side with plain OpenCV (prints; never asserts times).
bench: $(STAMP) $(BYTECODE)
	for script in bench/bench_*.py; do echo "== $$script"; $(BIN)/python $$script || exit 1; done
