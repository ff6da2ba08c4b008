# Two set-up commands for a fresh machine: `make run` and `make test`.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test bench install clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	OPENBLAS_NUM_THREADS=1 $(BIN)/acmm simulate

test: $(STAMP)
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python -m pytest

bench: $(STAMP)
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/bench.py
	OPENBLAS_NUM_THREADS=1 $(BIN)/python scripts/compare_riccati.py
	OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg $(BIN)/python scripts/bench_sweep.py

clean:
	rm -rf $(VENV) runs build *.egg-info
