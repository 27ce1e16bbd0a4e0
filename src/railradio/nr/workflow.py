"""The nr config as the workflow's rules see it (kept out of the simulation code's
fingerprint: a change here re-runs nothing by itself)."""

from __future__ import annotations

SIM_KEYS = ("trajectory", "deployment", "radio", "antenna", "channel", "receiver",
            "receiver_variants", "traffic")
"""The sections of the ``nr`` config that define the simulated bursts."""


def sim_config(c: dict) -> dict:
    """The simulation-defining sections of an ``nr`` config (a rule's params)."""
    return {k: c[k] for k in SIM_KEYS if k in c}


def receiver_selection(c: dict) -> dict[str, str]:
    """Receiver name -> the strength measure choosing its 3 measured RRHs."""
    return {"seed": c["receiver"]["selection"]} | {
        name: v["selection"] for name, v in c.get("receiver_variants", {}).items()}


def case_shard_paths(case: str, case_cfg: dict, main_cfg: dict, real: str, n_cal_shards: int,
                     n_case_shards: int) -> list[str]:
    """Estimate shards a sensitivity case's calibration (``real="cal"``) or track
    (``real="r0"``) reads: the main run's own when the case changes nothing that the
    bursts or the calibration run depend on (a tracker-only case), else the case's."""
    same = (sim_config(case_cfg) == sim_config(main_cfg)
            and case_cfg["calibration"] == main_cfg["calibration"])
    if same:
        n = n_cal_shards if real == "cal" else int(main_cfg["n_shards"])
        return [f"results/nr/estimates/{real}/s{k}.nc" for k in range(n)]
    n = n_cal_shards if real == "cal" else n_case_shards
    return [f"results/nr/cases/{case}/estimates/{real}/s{k}.nc" for k in range(n)]
