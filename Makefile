# railradio — set-up and entry points.  Every target bootstraps .venv when missing.
PYTHON ?= python3.11
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
JOBS   ?= 2
# workflow/Snakefile (Snakemake's standard layout): found from the repository root, with its
# default profile workflow/profiles/default (2 cores, rerun triggers, greedy scheduler)
SNAKE  := $(BIN)/snakemake
# CONFIG=my.yaml: a config file stating only what changes, laid over config/config.yaml
# (figures, numbers, paper, report; reproduce and expected keep their own scale)
CONFIG ?=
OVERRIDE := $(if $(CONFIG),--configfile $(CONFIG))
RUFF_PATHS := src workflow tests benchmarks
# the test suite on pytest-xdist workers, tests with a shared fixture kept together
# (tests/conftest.py); TEST_WORKERS=0: one process
TEST_WORKERS ?= 2
PYTEST_PAR := $(if $(filter 0,$(TEST_WORKERS)),,-n $(TEST_WORKERS) --dist loadgroup)
# snakefmt (pyproject.toml [tool.snakefmt]) finds workflow/Snakefile and workflow/rules/*.smk
SMK_PATHS  := workflow
export HDF5_USE_FILE_LOCKING := FALSE
export MPLBACKEND := Agg

.PHONY: all figures numbers paper test test-fast bench reproduce report lint expected publish fidelity records republish dag gallery clean

all: figures numbers

$(STAMP): pyproject.toml constraints.txt
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --disable-pip-version-check -c constraints.txt -e '.[test]'
	touch $(STAMP)

figures: $(STAMP)  ## every paper figure at paper scale (CONFIG=my.yaml: with your overrides)
	$(SNAKE) figures -j$(JOBS) $(OVERRIDE)

numbers: $(STAMP)  ## results/key_numbers.json and results/paper/numbers.tex
	$(SNAKE) numbers -j$(JOBS) $(OVERRIDE)

paper: $(STAMP)  ## results/paper/main.pdf (needs latexmk, see README)
	$(SNAKE) paper -j$(JOBS) $(OVERRIDE)

report: figures numbers  ## results/report.html
	$(SNAKE) all --report results/report.html $(OVERRIDE)

lint: $(STAMP)  ## ruff (lint and format, pyproject.toml), snakefmt (the workflow's format) and Snakemake's linter
	$(BIN)/ruff check $(RUFF_PATHS)
	$(BIN)/ruff format --check $(RUFF_PATHS)
	$(BIN)/snakefmt --check $(SMK_PATHS)
	$(BIN)/snakemake --lint

# Snakemake's linter and the paper-scale dry run are pytest's tests (tests/test_workflow.py:
# test_lint_is_clean, test_paper_scale_dag_resolves), not run a second time before it
test: $(STAMP)  ## lint, dry runs, unit + integration tests, CI-scale pipeline, key numbers
	$(BIN)/ruff check $(RUFF_PATHS)
	$(BIN)/ruff format --check $(RUFF_PATHS)
	$(BIN)/snakefmt --check $(SMK_PATHS)
	$(BIN)/python -m pytest $(PYTEST_PAR)

test-fast: $(STAMP)  ## unit tests only
	$(BIN)/python -m pytest $(PYTEST_PAR) -m "not slow"

bench: $(STAMP)  ## benchmarks -> results/benchmarks/*.json
	$(BIN)/python benchmarks/bench_fusion.py --out results/benchmarks/fusion_bench.json
	OPENBLAS_NUM_THREADS=1 $(BIN)/python benchmarks/bench_nr.py --out results/benchmarks/nr_bench.json
	$(BIN)/python benchmarks/bench_handover.py --out results/benchmarks/handover_bench.json
	$(BIN)/python benchmarks/bench_chain.py --out results/benchmarks/chain_bench.json
	OPENBLAS_NUM_THREADS=1 $(BIN)/python benchmarks/bench_tunnel.py --out results/benchmarks/tunnel_bench.json

reproduce: $(STAMP)  ## paper scale from nothing, compared with paper/numbers.json
	$(SNAKE) numbers -j$(JOBS) --forceall
	$(BIN)/python -m railradio.keynumbers results/key_numbers.json paper/numbers.json

expected: $(STAMP)  ## regenerate tests/expected/key_numbers_ci.json (CI scale, private dir)
	d=$$(mktemp -d) && cp -r workflow config paper src $$d/ && \
	  (cd $$d && $(CURDIR)/$(BIN)/snakemake numbers -j$(JOBS) \
	     --configfile config/ci.yaml -q rules) && \
	  cp $$d/results/key_numbers.json tests/expected/key_numbers_ci.json && rm -rf $$d

publish: numbers  ## copy the paper-scale key numbers to paper/numbers.json and regenerate docs/keys.md (commit both)
	cp results/key_numbers.json paper/numbers.json
	$(BIN)/python -m railradio.keytable docs paper/numbers.json docs/keys.md

# publishing the nr records from results/ (the targets records, fidelity and republish)
define PUBLISH_MAP_CASES
$(BIN)/python -m railradio.nr.study.records publish map results/nr/map/key_numbers.json
$(BIN)/python -m railradio.nr.study.records publish cases results/nr/cases/key_numbers.json
endef
define PUBLISH_FIDELITY
$(BIN)/python -m railradio.nr.study.records publish fidelity results/nr/fidelity/key_numbers.json
cp results/nr/fidelity/nr_fidelity.png docs/gallery/
endef

records: $(STAMP)  ## the nr reproduction map and sensitivity cases at paper scale -> paper/{map,cases}_numbers.json (commit them)
	$(SNAKE) records -j$(JOBS)
	$(PUBLISH_MAP_CASES)

fidelity: $(STAMP)  ## the nr shortcuts measured at paper scale (outside all) -> paper/fidelity_numbers.json (commit it)
	$(SNAKE) fidelity -j$(JOBS)
	$(PUBLISH_FIDELITY)

# After a change to code or config in an nr record's closure: the three records from one
# paper-scale run (both cores busy), published; then every paper-scale key number merged with
# the new records (a merge that ran before them would carry the old ones); then the CI-scale
# expectation, whose merge reads the fidelity record too
republish: $(STAMP)  ## the nr records, paper/numbers.json and tests/expected after an nr change (commit paper/, docs/, tests/expected/)
	$(SNAKE) records fidelity -j$(JOBS)
	$(PUBLISH_MAP_CASES)
	$(PUBLISH_FIDELITY)
	$(MAKE) publish
	$(MAKE) expected

GALLERY := fusion_rmse_vs_distance nr_position_error_cdf nr_sensitivity tunnel_position_error_cdf \
           tunnel_source_vs_physical handover_stages_vs_speed nr_sweeps chain_success_vs_sigma \
           nr_reproduction_map nr_conditions

dag: $(STAMP)  ## docs/workflow/<target>.md: each target's rule graph (Snakemake's Mermaid output)
	SNAKEMAKE=$(BIN)/snakemake docs/workflow/make_rulegraphs.sh

gallery: figures  ## docs/gallery/*.png: the README's figures, from a paper-scale run (commit them)
	mkdir -p docs/gallery && for f in $(GALLERY); do cp results/figures/$$f.png docs/gallery/; done

clean:
	rm -rf results .snakemake
