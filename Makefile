# Two commands set everything up on a fresh machine: `make demo` and `make test`.
# Both create .venv if needed and install the project into it; nothing is installed by hand.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.deformap-installed
EXTRAS ?= test,ros,rerun,dask

.PHONY: demo test bench lint clean venv

venv: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[$(EXTRAS)]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/deformap explore --scenario heterogeneous-60-110-rigid

# The tests run in TEST_WORKERS processes, each with BLAS pinned to one thread (the machines are shared).
TEST_WORKERS ?= 2
test: $(STAMP)
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 \
		$(PY) -m pytest -q -p no:cacheprovider -n $(TEST_WORKERS)

# Speed and memory tables, each with its baseline (benchmarks/README.md); JSON in benchmarks/results.
bench: $(STAMP)
	$(PY) benchmarks/run.py --json-dir benchmarks/results

lint: $(STAMP)
	$(PY) -m pip install --quiet 'ruff>=0.5' 'mypy>=1.10'
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/mypy

clean:
	rm -rf $(VENV) build dist src/*.egg-info .pytest_cache
