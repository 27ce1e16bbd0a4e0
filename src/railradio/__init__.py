"""railradio — radio positioning and handover for high-speed railways.

The science lives in one subpackage per study (``railradio.fusion``, ...); the shared
pieces are :mod:`railradio.rng` (seeding), :mod:`railradio.io` (NetCDF with provenance,
atomic writes), :mod:`railradio.config` (schema validation), :mod:`railradio.keynumbers`
and :mod:`railradio.plotting`.  Nothing here imports Snakemake.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
