# Two commands do all the set-up on a fresh machine:
#   make run    create .venv if needed, install, run the study (config/config.yaml)
#   make test   same environment; lint and the test suite (with the docs' examples and site)
#   make docs   the documentation site, docs/_build/html (warnings are errors)
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
CORES ?= 2
CONFIG ?= config/config.yaml
export OPENBLAS_NUM_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
export MKL_NUM_THREADS ?= 1

.PHONY: run test test-cluster test-verification lint bench docs docs-check clean-results

$(BIN)/python:
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \
		{ echo "Python >= 3.11 is required (set PYTHON=...)"; exit 1; }
	$(PYTHON) -m venv $(VENV)

$(STAMP): $(BIN)/python pyproject.toml requirements.lock
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --upgrade pip
	$(BIN)/python -m pip install --quiet --disable-pip-version-check \
		--constraint requirements.lock --editable '.[test,docs]'
	@touch $(STAMP)

run: $(STAMP)
	$(BIN)/snakemake --cores $(CORES) --configfile $(CONFIG)
	$(BIN)/snakemake --configfile $(CONFIG) --report results/report.html

lint: $(STAMP)
	$(BIN)/ruff check --quiet .
	$(BIN)/lint-imports --no-cache
	$(BIN)/snakefmt --check --compact-diff Snakefile rules/

# both cores: one test file per worker, so a file's module fixtures (a study run) run once
test: lint
	$(BIN)/pytest -q -n $(CORES) --dist loadfile

# The documentation site (Sphinx): every warning is an error. docs-check also checks
# that every internal link, anchor, image and API cross-reference of the built site
# resolves (tests/docs/test_site.py runs the same build and check in make test).
docs: $(STAMP)
	$(BIN)/sphinx-build -W --keep-going -q -b html docs docs/_build/html

docs-check: docs
	$(BIN)/python docs/check_links.py docs/_build/html

# profiles/slurm against a real Slurm: a throw-away one-node cluster (root; installs
# slurm-wlm and munge with apt-get if missing) runs Fig 14 of config/quick.yaml.
test-cluster: $(STAMP)
	$(BIN)/pytest -q -m slurm -rP --durations=0 tests/workflow/test_slurm_cluster.py

# The verification matrix's seeded set (tests/contact/test_verification_seeded.py, minutes):
# every operator x method x control x cap on more seeds and harder blocks than make test's.
test-verification: $(STAMP)
	$(BIN)/pytest -q -n $(CORES) -m verification tests/contact/test_verification_seeded.py

# Benchmarks (minutes; results in results/benchmarks/). QUICK=1 for a short run.
bench: $(STAMP)
	$(BIN)/python benchmarks/bench_influence.py $(if $(QUICK),--quick)
	$(BIN)/python benchmarks/bench_contact.py $(if $(QUICK),--quick)
	$(BIN)/python benchmarks/bench_operators.py $(if $(QUICK),--quick)

clean-results:
	rm -rf results .snakemake
