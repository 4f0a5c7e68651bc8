# bvhbench: the few commands a newcomer needs. `make help` lists them.
#   make bench   install what is missing, build the runner, make the default data, run the default suite, write the report
#   make test    install what is missing, build everything, run every C++ and Python test and the CI regression gate

SHELL       := /bin/bash
# Python: every Python step runs in the project's virtual environment $(VENV), made from $(PYTHON)
# by tools/python_env.sh (Debian's python3 refuses pip installs into the system, PEP 668).
PYTHON      ?= python3
VENV        ?= .venv
VPY         := $(VENV)/bin/python
BUILD_DIR   ?= build
BUILD_TYPE  ?= Release
JOBS        ?= $(shell nproc)
CMAKE_ARGS  ?=
BVHBENCH    := $(BUILD_DIR)/bvhbench
SUDO        := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

# Debian 12 packages the build needs (checked one by one; only the missing ones are installed).
# python3-venv: Debian's python3 makes virtual environments only with it. libusb-1.0-0: Open3D's
# library links it (the open3d method).
APT_PACKAGES := cmake ninja-build g++ make pkg-config git python3 python3-venv \
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libembree-dev libopenvdb-dev libtbb-dev \
  libeigen3-dev libgtest-dev libcli11-dev nlohmann-json3-dev libyaml-cpp-dev zlib1g-dev libssl-dev \
  python3-dev pybind11-dev libusb-1.0-0
# What only `make test` needs beyond them: a real browser, in which the report's HTML is
# opened, and valgrind, under which the gate counts instructions per query.
TEST_APT_PACKAGES := chromium valgrind

# One apt-get for the packages of $(1) that are not installed yet (checked one by one).
define apt_install
	@missing=$$(for p in $(1); do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q "install ok installed" || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "deps: installing Debian packages:" $$missing; \
	  $(SUDO) apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing >/dev/null || exit 1; \
	fi
endef

.PHONY: help deps test-deps venv build build-runner test test-cpp test-python gate bench estimate sweeps python data stability large paper huge rebaseline fixture calibration report clean distclean

help:
	@echo "make bench      - install, build the runner, make default data, run the default suite, write results/default/report/ (about 12 minutes from a fresh clone on 2 cores)"
	@echo "make estimate   - how long the default suite (or SUITE=NAME) is expected to take here, without running it"
	@echo "make sweeps     - the wide sweeps of every knob (suites/sweeps.yml) into results/sweeps/ with its report"
	@echo "make python     - the Python methods, one call per query and batched, also on the 1M bunny (suites/python.yml)"
	@echo "make test       - install (Chromium too: the report's browser test), build, run C++ (ctest) and Python (pytest) tests, then the CI regression gate"
	@echo "make deps       - install missing Debian packages, and Python packages into $(VENV)/ (idempotent, quiet when all present)"
	@echo "make build      - configure and build $(BVHBENCH) and every test ($(BUILD_TYPE))"
	@echo "make stability  - the stability suite: every method on every stress mesh"
	@echo "make large      - every method on a closed 4M-triangle model (about 15 minutes)"
	@echo "make paper      - the paper's tables at 32M triangles: data, out-of-core stores, suite, report (its expected time printed first)"
	@echo "make huge       - the EBP-Octree out of core on a 128M-triangle model: generate, build the store in 1 GiB, query from 256 MiB"
	@echo "make rebaseline - regenerate the committed CI baseline (results/baseline/) on purpose"
	@echo "make fixture    - regenerate the report tests' result fixture (tests/fixtures/results_small/) on purpose"
	@echo "make calibration - remake results/calibration/, the 1M-triangle runs every suite's expected time is priced from"

deps:
	$(call apt_install,$(APT_PACKAGES))
	@tools/python_env.sh --python $(PYTHON) --venv $(VENV)

test-deps:
	$(call apt_install,$(TEST_APT_PACKAGES))

# The Python environment alone (for the Python-only targets run by hand).
venv:
	@tools/python_env.sh --python $(PYTHON) --venv $(VENV)

$(BUILD_DIR)/build.ninja:
	cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_ARGS)

build: deps $(BUILD_DIR)/build.ninja
	cmake --build $(BUILD_DIR) -j $(JOBS)

# The runner alone (with every method it hosts), without the C++ tests and fuzz replayers: what
# `make bench` and the suites need. The same build folder as `make build`, which adds the rest.
build-runner: deps $(BUILD_DIR)/build.ninja
	cmake --build $(BUILD_DIR) -j $(JOBS) --target bvhbench

test: build test-deps test-cpp test-python gate

# The venv's bin/ comes first on PATH, so that a C++ test that checks its files with NumPy finds it.
test-cpp:
	PATH=$(abspath $(VENV))/bin:$$PATH ctest --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

test-python:
	BVHBENCH_EXE=$(abspath $(BVHBENCH)) $(VPY) -m pytest tests/python

# CI regression gate: counters, accuracy and statuses against results/baseline/ (timings reported only),
# then instructions per query under valgrind against results/instr-baseline/ (docs/compare.md).
gate:
	@if [ -x tools/ci_gate.sh ]; then PATH=$(abspath $(VENV))/bin:$$PATH BVHBENCH_EXE=$(abspath $(BVHBENCH)) tools/ci_gate.sh; \
	 else echo "gate: tools/ci_gate.sh not present yet; skipped"; fi

data: deps
	$(VPY) datasets-scripts/make_datasets.py --preset default

report: venv
	$(VPY) plots/report.py results/default

# $(call run_suite,NAME): suites/NAME.yml into results/NAME/ (the runner says first how long it
# expects to take, and corrects it after each job), then its report.
define run_suite
	$(BVHBENCH) suite suites/$(1).yml --out results/$(1) --resume
	$(VPY) plots/report.py results/$(1)
	@echo "report: results/$(1)/report/report.md and report.html"
endef

# The default suite reads one generated model (the others are ../shared/meshes): only it is made.
BENCH_MODELS := bunny_closed_1m

bench: build-runner
	$(VPY) datasets-scripts/make_datasets.py --preset default --only $(BENCH_MODELS)
	$(call run_suite,default)

# How long the default suite (or SUITE=NAME) is expected to take here, without running it.
SUITE ?= default
estimate: build-runner
	$(BVHBENCH) suite suites/$(SUITE).yml --out results/$(SUITE) --resume --estimate

sweeps: build-runner data
	$(call run_suite,sweeps)

python: build-runner data
	$(call run_suite,python)

stability: build-runner
	$(VPY) datasets-scripts/make_datasets.py --preset stability
	$(BVHBENCH) suite suites/stability.yml --out results/stability --resume
	$(VPY) tools/stability_matrix.py results/stability
	$(VPY) plots/report.py results/stability

large: build-runner
	$(VPY) datasets-scripts/make_datasets.py --preset large
	$(BVHBENCH) suite suites/large.yml --out results/large --resume
	$(VPY) plots/report.py results/large

# $(call build_stores,DIR,MODELS): DIR/M.ebp built out of core (1 GiB budget, 2 threads) for each
# model M whose store is missing or older than DIR/M.ply, each announced with its expected time:
# STORE_S_PER_MTRI seconds per million triangles (measured alone on 2 cores: 0.9 s for the 1M
# bunny, 98 s for the 128M scan-like model; the external build is about linear in the
# triangles), then its time.
STORE_S_PER_MTRI := 1
define build_stores
	@for m in $(2); do \
	  if [ ! -f $(1)/$$m.ebp ] || [ $(1)/$$m.ply -nt $(1)/$$m.ebp ]; then \
	    tri=$$(head -c 4096 $(1)/$$m.ply | grep -a -m1 '^element face' | awk '{print $$3}'); \
	    echo "store: $(1)/$$m.ebp from $$tri triangles, expected ~$$(( $${tri:-0} * $(STORE_S_PER_MTRI) / 1000000 ))s"; \
	    t0=$$SECONDS; \
	    $(BVHBENCH) ebp build --mesh $(1)/$$m.ply --out $(1)/$$m.ebp --memory-budget 1024 --threads 2 || exit 1; \
	    echo "store: $(1)/$$m.ebp took $$((SECONDS - t0))s"; \
	  fi; \
	done
endef

# $(call timed,STEP,COMMAND): COMMAND, then how long STEP took (the split of a long target).
define timed
	@t0=$$SECONDS; $(2) || exit 1; echo "$(1) took $$((SECONDS - t0))s"
endef

PAPER_MODELS := bunny_closed_32m scan_like_32m

# The paper's tables: the two 32M-triangle models (each announced with its expected time), their
# out-of-core stores, the suite (which prints its expected time before it starts: `make estimate
# SUITE=paper` alone, also before the data exists), the report. Each step says how long it took.
paper: build-runner
	@$(BVHBENCH) suite suites/paper.yml --out results/paper --resume --estimate
	$(call timed,paper: data,$(VPY) datasets-scripts/make_datasets.py --preset paper)
	$(call build_stores,data/paper,$(PAPER_MODELS))
	$(call timed,paper: suite,$(BVHBENCH) suite suites/paper.yml --out results/paper --resume)
	$(call timed,paper: report,$(VPY) plots/report.py results/paper)

# Beyond the paper: 128M triangles, generated in chunks (2.4 GB of PLY), the store built out of
# core within a 1 GiB budget (its vertices paged; ≈ 12 GB on disk, with ≈ 3.6 GB of sort runs
# while it builds), then suites/huge.yml from a 256 MiB page cache, its haptic path made on a
# paged copy of the mesh (≈ 4 GB of temporary files): every step within 1 GiB. About 5 minutes on
# 2 idle cores (generation 2, store 2, queries 1).
HUGE_MODELS := scan_like_128m

huge: build-runner
	$(VPY) datasets-scripts/make_datasets.py --preset huge
	$(call build_stores,data/huge,$(HUGE_MODELS))
	$(BVHBENCH) suite suites/huge.yml --out results/huge --resume
	$(VPY) plots/report.py results/huge

# The results every suite's expected time is priced from (suites/calibration.yml), remade on
# purpose; then commit results/calibration/runs and summary.csv.
calibration: build-runner
	$(VPY) datasets-scripts/make_datasets.py --preset default --only $(BENCH_MODELS)
	mkdir -p results/calibration/data
	$(BVHBENCH) ebp build --mesh data/default/bunny_closed_1m.ply --out results/calibration/data/bunny_closed_1m.ebp --memory-budget 1024 --threads 2
	rm -rf results/calibration/runs results/calibration/summary.csv
	$(BVHBENCH) suite suites/calibration.yml --out results/calibration

rebaseline: build test-deps
	@if [ -x tools/ci_gate.sh ]; then PATH=$(abspath $(VENV))/bin:$$PATH BVHBENCH_EXE=$(abspath $(BVHBENCH)) tools/ci_gate.sh --rebaseline; \
	 else echo "rebaseline: tools/ci_gate.sh not present yet"; exit 1; fi

# The report tests' fixture is a real suite run; a change of parameters, job ids or result keys
# makes tests/python/plots/test_report_fixture.py ask for this.
fixture: build
	BVHBENCH_EXE=$(abspath $(BVHBENCH)) $(VPY) tests/fixtures/results_small/make_fixture.py

clean:
	rm -rf $(BUILD_DIR)

# The Python environment too (made again by the next `make deps`).
distclean: clean
	rm -rf $(VENV)
