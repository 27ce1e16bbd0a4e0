# Shared set-up: config validation before any job, code fingerprints, target registries.
import os
from pathlib import Path

from railradio.workflow import JOB_ENV

# One BLAS thread per job and a heap that keeps freed memory (railradio.workflow.JOB_ENV);
# the jobs' processes inherit it. A value already in the environment wins.
for _var, _value in JOB_ENV.items():
    os.environ.setdefault(_var, _value)

from railradio.config import load_schema, validate_config
from railradio.workflow import code_hash

validate_config(
    config, load_schema(Path(workflow.basedir) / "workflow/schemas/config.schema.yaml")
)

# Each study's rule file registers its figures and key-number fragment here.
STUDY_FIGURES = {}
KEY_NUMBER_FRAGMENTS = []
FIGURES = []

# Library fingerprints shared by every study (see railradio.workflow.code_hash).
CODE_SHARED = code_hash("railradio.io", "railradio.rng", "railradio.constants")
CODE_PLOT = code_hash("railradio.plotting")


def register_figures(study, names):
    """Register a study's figures (PDF and PNG) as targets."""
    paths = [f"results/figures/{n}.{ext}" for n in names for ext in ("pdf", "png")]
    STUDY_FIGURES[study] = paths
    FIGURES.extend(paths)
