"""Adapter: a sensitivity case's estimates (r0) + its calibration -> its tracks (track.py
on the case's epochs, TOAs with the case's clock errors)."""

import sys

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from case_common import run_main_script

run_main_script(snakemake, "track.py", rid=0)  # noqa: F821
