# Two set-up commands for a fresh machine: `make run` and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test bench report report-fast browser install bytecode clean

# the package's own modules as bytecode: with PYTHONDONTWRITEBYTECODE set (as on CI machines) an
# editable install would otherwise compile them from source at every command (~0.1 s a run;
# compileall only rewrites what changed)
PACKAGES := acmm qpp common cli report configkinds

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	OPENBLAS_NUM_THREADS=1 $(BIN)/python -m acmm.warmup
	touch $(STAMP)

install: $(STAMP) bytecode

bytecode: $(STAMP)
	@$(BIN)/python -m compileall -q $(PACKAGES)

run: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 $(BIN)/acmm simulate

# In CI (CI=true) the report test also opens the page in a real headless Chromium (Debian's
# package); elsewhere that test is skipped unless /usr/bin/chromium exists.
test: $(STAMP) bytecode $(if $(CI),browser)
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python -m pytest

browser:
	@test -x /usr/bin/chromium || { command -v apt-get >/dev/null && [ "$$(id -u)" = 0 ] && \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } || \
	  echo "chromium not installed: the browser test will be skipped"

bench: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/bench.py
	OPENBLAS_NUM_THREADS=1 $(BIN)/python scripts/compare_riccati.py
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/bench_sweep.py
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/bench_ratios.py --full

report: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/acmm report

report-fast: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/acmm report --fast

clean:
	rm -rf $(VENV) runs build *.egg-info

# The README's generated tables (<!-- generated:NAME --> blocks) from a fresh run of the packaged
# configs in a temporary results root (scripts/readme_numbers.py; tests/test_readme_numbers.py checks them)
.PHONY: readme
readme: $(STAMP) bytecode
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/readme_numbers.py
