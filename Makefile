# bvhbench: the few commands a newcomer needs. `make help` lists them.
#   make bench   install what is missing, build, make the default data, run the default suite, write the report
#   make test    install what is missing, build, run every C++ and Python test and the CI regression gate

SHELL       := /bin/bash
PYTHON      ?= python3
BUILD_DIR   ?= build
BUILD_TYPE  ?= Release
JOBS        ?= $(shell nproc)
CMAKE_ARGS  ?=
BVHBENCH    := $(BUILD_DIR)/bvhbench
SUDO        := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

# Debian 12 packages the build needs (checked one by one; only the missing ones are installed).
APT_PACKAGES := cmake ninja-build g++ make pkg-config git \
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libembree-dev libopenvdb-dev libtbb-dev \
  libeigen3-dev libgtest-dev libcli11-dev nlohmann-json3-dev libyaml-cpp-dev zlib1g-dev

.PHONY: help deps build test test-cpp test-python gate bench data stability large paper rebaseline report clean

help:
	@echo "make bench      - install, build, make default data, run the default suite, write results/default/report/"
	@echo "make test       - install, build, run C++ (ctest) and Python (pytest) tests, then the CI regression gate"
	@echo "make deps       - install missing Debian and Python packages (idempotent, quiet when all present)"
	@echo "make build      - configure and build $(BVHBENCH) ($(BUILD_TYPE))"
	@echo "make stability  - the stability suite: every method on every stress mesh"
	@echo "make large      - every method on a closed 4M-triangle model (about 15 minutes)"
	@echo "make paper      - the paper's tables at 30M+ triangles (about an hour)"
	@echo "make rebaseline - regenerate the committed CI baseline (results/baseline/) on purpose"

deps:
	@missing=$$(for p in $(APT_PACKAGES); do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q "install ok installed" || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "deps: installing Debian packages:" $$missing; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing >/dev/null || exit 1; \
	fi
	@missing=$$($(PYTHON) tools/pydeps.py --missing); \
	if [ -n "$$missing" ]; then \
	  echo "deps: installing Python packages:" $$missing; \
	  $(PYTHON) -m pip install -q --disable-pip-version-check $$missing || exit 1; \
	fi

$(BUILD_DIR)/build.ninja:
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

build: deps $(BUILD_DIR)/build.ninja
	cmake --build $(BUILD_DIR) -j $(JOBS)

test: build test-cpp test-python gate

test-cpp:
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

test-python:
	BVHBENCH_EXE=$(abspath $(BVHBENCH)) $(PYTHON) -m pytest tests/python

# CI regression gate: counters, accuracy and statuses against results/baseline/ (timings reported only).
gate:
	@if [ -x tools/ci_gate.sh ]; then BVHBENCH_EXE=$(abspath $(BVHBENCH)) tools/ci_gate.sh; \
	 else echo "gate: tools/ci_gate.sh not present yet; skipped"; fi

data: deps
	$(PYTHON) datasets-scripts/make_datasets.py --preset default

report:
	$(PYTHON) plots/report.py results/default

bench: build data
	$(BVHBENCH) suite suites/default.yml --out results/default --resume
	$(PYTHON) plots/report.py results/default
	@echo "report: results/default/report/report.md"

stability: build
	$(PYTHON) datasets-scripts/make_datasets.py --preset stability
	$(BVHBENCH) suite suites/stability.yml --out results/stability --resume
	$(PYTHON) tools/stability_matrix.py results/stability
	$(PYTHON) plots/report.py results/stability

large: build
	$(PYTHON) datasets-scripts/make_datasets.py --preset large
	$(BVHBENCH) suite suites/large.yml --out results/large --resume
	$(PYTHON) plots/report.py results/large

PAPER_MODELS := bunny_closed_32m scan_like_32m

paper: build
	$(PYTHON) datasets-scripts/make_datasets.py --preset paper
	@for m in $(PAPER_MODELS); do \
	  if [ ! -f data/paper/$$m.ebp ] || [ data/paper/$$m.ply -nt data/paper/$$m.ebp ]; then \
	    $(BVHBENCH) ebp build --mesh data/paper/$$m.ply --out data/paper/$$m.ebp --memory-budget 1024 --threads 2 || exit 1; \
	  fi; \
	done
	$(BVHBENCH) suite suites/paper.yml --out results/paper --resume
	$(PYTHON) plots/report.py results/paper

rebaseline: build
	@if [ -x tools/ci_gate.sh ]; then BVHBENCH_EXE=$(abspath $(BVHBENCH)) tools/ci_gate.sh --rebaseline; \
	 else echo "rebaseline: tools/ci_gate.sh not present yet"; exit 1; fi

clean:
	rm -rf $(BUILD_DIR)
