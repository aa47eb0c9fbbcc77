# rheolin: `make demo` and `make test` work on a fresh machine with nothing but python3.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint typecheck pytest bench clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/rheolin example gearbox > demo_gearbox.toml
	$(BIN)/rheolin run demo_gearbox.toml --out demo_results/run
	$(BIN)/rheolin sweep demo_gearbox.toml --speeds 1500:4500:500rpm \
		--out demo_results/sweep

lint: $(STAMP)
	$(BIN)/ruff check src tests bench docs/figures.py docs/gallery/make.py
	$(BIN)/ruff format --check src tests bench docs/figures.py docs/gallery/make.py

typecheck: $(STAMP)
	$(BIN)/mypy src

pytest: $(STAMP)
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 $(BIN)/pytest -n auto

test: lint typecheck pytest

bench: $(STAMP)
	$(BIN)/python bench/solvers.py

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache build src/*.egg-info
