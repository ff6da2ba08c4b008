# Two set-up commands for a fresh machine: `make run` and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# exact versions with hashes of every package the project and its tests use (`make lock` refreshes it)
LOCK   := requirements.lock
# `make lock` runs uv at this version, from a venv of its own (not the project's)
UV_VERSION := 0.13.9
UV_VENV    := .venv-uv
# `make test-latest`: the newest releases instead of the lock, in a venv of their own
LATEST     := .venv-latest

# OpenBLAS's kernel: the README's and the guide's generated numbers are those of its Haswell kernel
# (docs/reproducibility.md); on an AVX-512 machine it would pick SkylakeX, whose rounding moves
# the qpp examples' procedure 12.1 trails and the family search's grid counts (measured).  Pinned
# where the CPU has AVX2 (a kernel the CPU lacks would crash); a value in the environment wins.
BLAS_KERNEL := $(shell grep -qw avx2 /proc/cpuinfo 2>/dev/null && echo Haswell)
ifneq ($(BLAS_KERNEL),)
export OPENBLAS_CORETYPE ?= $(BLAS_KERNEL)
endif

.PHONY: run test test-slow test-latest lock bench report report-fast browser install bytecode clean docs docs-figures

# the package's own modules as bytecode: with PYTHONDONTWRITEBYTECODE set (as on CI machines) an
# editable install would otherwise compile them from source at every command (~0.1 s a run;
# compileall only rewrites what changed)
PACKAGES := acmm qpp acmm_qpp

# the dependencies exactly as locked (pip refuses any file whose hash is not in the lock), then the
# project itself without resolving anything
$(STAMP): pyproject.toml $(LOCK)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet --require-hashes -r $(LOCK)
	$(BIN)/python -m pip install --quiet --no-deps -e .
	OPENBLAS_NUM_THREADS=1 $(BIN)/python -m acmm.simulate.warmup
	touch $(STAMP)

install: $(STAMP) bytecode

bytecode: $(STAMP)
	@$(BIN)/python -m compileall -q $(PACKAGES)

run: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 $(BIN)/acmm simulate
	@echo "figures: runs/staircase/sim_summary.png (and the other runs/staircase/*.png)"
	@echo "to use acmm and qpp from this shell: source $(VENV)/bin/activate"

# In CI (CI=true) the report test also opens the page in a real headless Chromium (Debian's
# package); elsewhere that test is skipped unless /usr/bin/chromium exists.
# --durations: the slowest tests are printed at the end of every run (CI's output included).
# `make test` leaves out the system tests marked slow (whole reports, the cross-kernel runs, timed
# signals, the generated numbers' regeneration, the README's quick start, the longest subprocess and fuzz runs); `make test-slow` runs
# them, and CI (.ci/run) runs both.
# Both run in $(TEST_WORKERS) pytest-xdist worker processes, one per core of the 2-core machines CI
# runs on (`make test TEST_WORKERS=auto` on a larger one).  `make test` hands out tests and lets
# an idle worker take the other's queued ones (--dist worksteal: with --dist load one worker sat idle
# while the other ran its last chunk); `make test-slow` hands out a file at a time,
# and the files that name the same costly session fixture to the same worker (--dist loadgroup:
# tests/conftest.py's work_unit).
TEST_WORKERS ?= 2
PYTEST := OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python -m pytest -n $(TEST_WORKERS)

test: $(STAMP) bytecode $(if $(CI),browser)
	$(PYTEST) --dist worksteal -m "not slow" --durations=25

test-slow: $(STAMP) bytecode
	$(PYTEST) --dist loadgroup -m slow --durations=10

# The suite against the newest releases within pyproject.toml's bounds, in $(LATEST) (re-resolved at
# every call; not part of CI): what the next `make lock` would bring.  The numba cache beside the
# sources is shared with .venv: after a run here with another numba, the next `make test`
# compiles the kernels once again.
test-latest:
	$(PYTHON) -m venv $(LATEST)
	$(LATEST)/bin/python -m pip install --quiet --upgrade pip
	$(LATEST)/bin/python -m pip install --quiet --upgrade -e '.[test]'
	$(LATEST)/bin/python -m pip list --format=freeze | grep -iE '^(numpy|scipy|control|slycot|numba)=='
	OPENBLAS_NUM_THREADS=1 $(LATEST)/bin/python -m acmm.simulate.warmup
	@$(LATEST)/bin/python -m compileall -q $(PACKAGES)
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(LATEST)/bin/python -m pytest --durations=25

# Refresh $(LOCK): the newest releases within pyproject.toml's bounds (main dependencies and the
# test extra), for every platform and every Python from 3.10 (pyproject's requires-python) on,
# with the hashes of every file.  Commit the new lock together with the README's table
# (`python scripts/lock_table.py --write`; tests/test_lock.py fails until they agree).
$(UV_VENV)/.uv-$(UV_VERSION):
	$(PYTHON) -m venv $(UV_VENV)
	$(UV_VENV)/bin/python -m pip install --quiet uv==$(UV_VERSION)
	touch $@

lock: $(UV_VENV)/.uv-$(UV_VERSION)
	UV_CUSTOM_COMPILE_COMMAND="make lock" $(UV_VENV)/bin/uv pip compile pyproject.toml --extra test \
	  --universal --python-version 3.10 --generate-hashes --upgrade --quiet -o $(LOCK)

browser:
	@test -x /usr/bin/chromium || { command -v apt-get >/dev/null && [ "$$(id -u)" = 0 ] && \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } || \
	  echo "chromium not installed: the browser test will be skipped"

bench: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/bench.py --only-targets
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/bench.py --only-ratios --full
	OPENBLAS_NUM_THREADS=1 $(BIN)/python scripts/compare_riccati.py

report: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/acmm report

report-fast: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/acmm report --fast

# The user guide (docs/, MkDocs + mkdocstrings) into site/; any warning fails the build
docs: $(STAMP)
	$(BIN)/python -m mkdocs build --strict --site-dir site

# The guide's figures (docs/img/*.png) from a fresh run in a temporary results root
docs-figures: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/docs_figures.py

clean:
	rm -rf $(VENV) $(LATEST) $(UV_VENV) runs build site *.egg-info

# The generated tables (<!-- generated:NAME --> blocks) of README.md and docs/**/*.md from a fresh
# run of the packaged configs in a temporary results root (scripts/readme_numbers.py;
# tests/test_readme_numbers.py checks them)
.PHONY: readme
readme: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/readme_numbers.py
