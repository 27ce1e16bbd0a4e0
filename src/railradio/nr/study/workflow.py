"""The nr config as the workflow's rules see it (kept out of the simulation code's
fingerprint: a change here re-runs nothing by itself)."""

from __future__ import annotations

SIM_KEYS = (
    "trajectory",
    "deployment",
    "radio",
    "antenna",
    "channel",
    "receiver",
    "extra_receivers",
    "traffic",
    "cell_search",
)
"""The sections of the ``nr`` config that define the simulated bursts and the estimates made of
them (the cell search names the measured RRHs)."""


def sim_config(c: dict) -> dict:
    """The simulation-defining sections of an ``nr`` config (a rule's params).

    Parameters
    ----------
    c : dict
        The ``nr`` section of the workflow config (or a sensitivity case's merged config).

    Returns
    -------
    dict
        The sections of ``c`` named in :data:`SIM_KEYS` that are present (same objects, not copies).
    """
    return {k: c[k] for k in SIM_KEYS if k in c}


def receiver_selection(c: dict) -> dict[str, str]:
    """Receiver name -> the strength measure choosing its 3 measured RRHs.

    Parameters
    ----------
    c : dict
        The ``nr`` section of the workflow config (or a sensitivity case's merged config).

    Returns
    -------
    dict of str to str
        ``"source"`` -> ``c["receiver"]["selection"]``, then each ``extra_receivers`` name -> its
        ``selection`` (config order).
    """
    return {"source": c["receiver"]["selection"]} | {
        name: v["selection"] for name, v in c.get("extra_receivers", {}).items()
    }


def case_shard_paths(
    case: str,
    case_cfg: dict,
    main_cfg: dict,
    real: str,
    n_cal_shards: int,
    n_case_shards: int,
    cases: dict | None = None,
) -> list[str]:
    """Estimate shards a sensitivity case's calibration (``real="cal"``) or track
    (``real="r0"``) reads: the main run's own when the case changes nothing that the
    bursts or the calibration run depend on (a tracker-only case), else those of the first
    case in ``cases`` (config order) with the same bursts, else the case's own.

    Parameters
    ----------
    case : str
        The case name.
    case_cfg, main_cfg : dict
        The case's merged ``nr`` config and the main one (``n_shards``).
    real : str
        ``"cal"`` (the calibration run) or ``"r0"`` (the track's realization).
    n_cal_shards : int
        Shards of a calibration run.
    n_case_shards : int
        Shards of a case's own r0 run.
    cases : dict or None
        Case name -> merged ``nr`` config, config order (``None``: none).

    Returns
    -------
    list of str
        Paths of the estimate shards (netCDF), shard order.
    """

    def same(a: dict, b: dict) -> bool:
        return sim_config(a) == sim_config(b) and a["calibration"] == b["calibration"]

    if same(case_cfg, main_cfg):
        n = n_cal_shards if real == "cal" else int(main_cfg["n_shards"])
        return [f"results/nr/estimates/{real}/s{k}.nc" for k in range(n)]
    owner = next((name for name, cfg in (cases or {}).items() if same(cfg, case_cfg)), case)
    n = n_cal_shards if real == "cal" else n_case_shards
    return [f"results/nr/cases/{owner}/estimates/{real}/s{k}.nc" for k in range(n)]
