# Shared set-up: config validation before any job, code fingerprints, target registries.
import os
from pathlib import Path

from railradio.arithmetic import PIN_KEYS
from railradio.workflow import JOB_ENV

# One BLAS thread per job, a heap that keeps freed memory, and NumPy's and OpenBLAS's code
# paths pinned so that the arithmetic does not depend on the CPU (railradio.workflow.JOB_ENV);
# the jobs' processes inherit it. A value already in the environment wins, except for the
# CPU pins, which the numbers depend on (RAILRADIO_CPU_PINS=0 leaves them out).
for _var, _value in JOB_ENV.items():
    if _var in PIN_KEYS:
        if os.environ.get("RAILRADIO_CPU_PINS", "1") != "0":
            os.environ[_var] = _value
    else:
        os.environ.setdefault(_var, _value)

from railradio.codedeps import script_code_hash
from railradio.config import load_schema, validate_config
from railradio.config_checks import check_config

# The repository root: the one place the workflow computes it. This file is
# <root>/workflow/rules/common.smk; its own directory (not workflow.basedir, the main
# Snakefile's, which a wrapper such as tests/test_codedeps.py's probe.smk moves) fixes it.
# The published records (railradio.published) hash their files relative to it.
REPO_ROOT = Path(workflow.current_basedir).parents[1]

# The schema (types, ranges, a default for every key), then the rules between keys: a bad
# value stops Snakemake here, naming the key, before any job. The check returns the nr
# sensitivity cases and map cells it merged and validated; nr.smk plans from them.
CONFIG_SCHEMA = load_schema(REPO_ROOT / "workflow/schemas/config.schema.yaml")
# A nested value given with --config (nr={...}) reaches the workflow with its leaves as
# strings, which the schema would reject one by one as "'8' is not of type 'integer'":
# name the cause and the way that works instead.
for _key, _value in dict(workflow.config_settings.config or {}).items():
    if isinstance(_value, dict):
        raise ValueError(
            f"--config {_key}=...: a nested value on the command line reaches the workflow with its "
            "values as strings, which the config schema rejects. Put nested overrides in a YAML file "
            f"that states only what changes (e.g. '{_key}: {{n_shards: 8}}') and pass it with "
            "--configfile my.yaml (make figures CONFIG=my.yaml); --config takes top-level values "
            "only (seed=7). See docs/configuration.md."
        )
validate_config(config, CONFIG_SCHEMA)
CONFIG_CHECKED = check_config(config, CONFIG_SCHEMA)

# Each study's rule file registers its figures and key-number fragment here.
STUDY_FIGURES = {}
KEY_NUMBER_FRAGMENTS = []
FIGURES = []


def register_figures(study, names):
    """Register a study's figures (PDF and PNG) as targets."""
    paths = [f"results/figures/{n}.{ext}" for n in names for ext in ("pdf", "png")]
    STUDY_FIGURES[study] = paths
    FIGURES.extend(paths)


def set_code_hashes(workflow_rules):
    """Set the ``code`` param of each scripted step to the hash of the library modules,
    helper scripts and data files its script reaches by imports (railradio.codedeps), so a
    step re-runs exactly when code it runs changes. Called once every step is defined."""
    for r in workflow_rules:
        if r.script is not None:
            script = Path(r.basedir.join(r.script).get_path_or_uri(secret_free=True))
            r.set_params(code=script_code_hash(script))
