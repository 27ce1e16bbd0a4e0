"""Adapter: a sensitivity case's calibration run -> its calibration.json (calibrate.py on
the case's calibration epochs, TOAs with the calibration run's own clock errors)."""

import sys

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from case_common import run_main_script

run_main_script(snakemake, "calibrate.py", rid=1000)  # noqa: F821
