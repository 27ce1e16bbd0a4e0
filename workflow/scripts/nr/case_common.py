"""Shared adapter code of the sensitivity-case scripts: the main run's calibrate.py /
track.py on the case's estimates, cut to the case's epochs, with the clock errors of the
case's ``nr.sync`` added to the measured TOAs (railradio.nr.clocks.apply_clock_errors)."""

import runpy
from pathlib import Path

import common

from railradio.nr.clocks import apply_clock_errors
from railradio.rng import spawn_key


def run_main_script(smk, script: str, rid: int) -> None:
    """Run ``script`` (calibrate.py or track.py) with its shard reader wrapped: the first
    ``smk.params.n_epochs`` epochs of realization ID ``rid`` (0: r0, 1000: the calibration
    run), clock errors keyed by that realization."""
    read = common.read_shards
    sync = dict(smk.params.sync)

    def read_case(paths):
        ds = read(paths).isel(epoch=slice(0, int(smk.params.n_epochs)))
        return apply_clock_errors(
            ds, int(smk.params.seed), spawn_key("nr", rid), float(sync["rrh_sigma_s"]), float(sync["train_bias_s"])
        )

    common.read_shards = read_case
    try:
        runpy.run_path(str(Path(__file__).parent / script), init_globals={"snakemake": smk})
    finally:
        common.read_shards = read
