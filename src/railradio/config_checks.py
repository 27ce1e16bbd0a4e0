"""Rules between config keys, which a JSON schema cannot state, checked before any job.

:func:`check_config` runs after the schema (:func:`railradio.config.validate_config`) on the
whole config and raises one :class:`~railradio.config.ConfigError` listing every broken
rule, each naming its key, the value and what the other keys allow. Two kinds of rule:

* cross-key rules written out here (shards ≤ epochs, batches ≤ blocks, a receiver that
  exists, a speed that is simulated, ascending grids, …);
* the studies' own parameter objects built from the config (``scenario_from_config`` and
  friends), which check physical consistency (a slot inside the tunnel, a track arc
  around its base stations); their ``ValueError`` is reported under the section's key.

The nr sensitivity cases are validated here too, each as the nr section with the case
merged in (:func:`railradio.nr.study.cases.merged_cases`), under ``nr.sensitivity.cases.<case>``,
and so are the cells of the nr reproduction map (:func:`railradio.nr.study.reproduction_map.cells`).
:func:`check_config` returns them (:class:`Checked`): the workflow plans its nr jobs from
these (:func:`railradio.nr.study.plan.nr_plan`), so each is merged and validated once.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from railradio.config import ConfigError, Validator
from railradio.nr.waveform.numerology import CP_NORMAL, N_FFT, SAMPLE_RATE_HZ

Problem = tuple[str, Any, str]
"""(dotted key, its value, what the rule allows)."""


@dataclass(frozen=True)
class Checked:
    """The nr configs the checks merged and validated, handed to the workflow so that it
    does not merge and validate them again (:func:`railradio.nr.study.plan.nr_plan` copies them).

    Attributes
    ----------
    nr_cases : dict of str to dict
        Sensitivity case name -> the nr section with the case merged in, schema-valid with
        the defaults filled (:func:`railradio.nr.study.cases.merged_cases`, config order).
    nr_map_cells : dict of str to dict
        Reproduction-map cell name -> its whole nr config, schema-valid
        (:func:`railradio.nr.study.reproduction_map.cells`, map order).
    """

    nr_cases: dict[str, dict[str, Any]]
    nr_map_cells: dict[str, dict[str, Any]]


def _get(cfg: Mapping[str, Any], key: str) -> Any:
    node: Any = cfg
    for part in key.split("."):
        node = node[part]
    return node


def _at_most(cfg: Mapping[str, Any], key: str, limit_key: str, limit: Any | None = None) -> Iterator[Problem]:
    value, lim = _get(cfg, key), _get(cfg, limit_key) if limit is None else limit
    if value > lim:
        yield key, value, f"<= {limit_key} = {lim!r}"


def _ascending(cfg: Mapping[str, Any], key: str) -> Iterator[Problem]:
    v = list(_get(cfg, key))
    if any(b <= a for a, b in zip(v, v[1:], strict=False)):
        yield key, v, "strictly ascending values"


def _probe(key: str, build: Callable[[], Any]) -> Iterator[Problem]:
    """Build a study's parameter object; its ValueError becomes a problem of ``key``."""
    try:
        build()
    except (ValueError, KeyError) as exc:
        yield key, "…", f"values the study accepts ({exc})"


# ---------------------------------------------------------------- the studies


def _fusion(cfg: Mapping[str, Any]) -> Iterator[Problem]:
    from railradio.fusion.arc import ArcGeometry

    f = cfg["fusion"]
    for i, r in enumerate(f["sensitivity"]["radii_m"]):
        yield from _probe(
            f"fusion.sensitivity.radii_m[{i}]",
            lambda r=r: ArcGeometry(f["reference"]["d_m"], r, f["cell_radius_factor"]),
        )


def main_epochs(nr: Mapping[str, Any]) -> int | None:
    """Epochs of an nr run: the trajectory's, cut at ``max_epochs`` (None if it is invalid).

    Parameters
    ----------
    nr : mapping
        The ``nr`` section of the config (schema-valid, defaults filled).

    Returns
    -------
    int or None
        Number of epochs of the run: the trajectory's, at most ``max_epochs`` when that is
        set; None if :func:`railradio.nr.engine.simulate.scenario_from_config` rejects the section
        (ValueError or KeyError).
    """
    from railradio.nr.engine.simulate import scenario_from_config

    try:
        n_traj = scenario_from_config(dict(nr)).trajectory.n_epochs
    except (ValueError, KeyError):
        return None
    return n_traj if nr["max_epochs"] is None else min(nr["max_epochs"], n_traj)


def nr_problems(nr: Mapping[str, Any], root: str = "nr", main: bool = True) -> Iterator[Problem]:
    """The rules of one nr config (the main run's, ``main=True``, or a merged case's).

    Parameters
    ----------
    nr : mapping
        An nr config, schema-valid: the ``nr`` section, or a sensitivity case or map cell
        merged into it.
    root : str, default "nr"
        Dotted key under which the problems are reported (e.g.
        ``"nr.sensitivity.cases.<case>"``).
    main : bool, default True
        True for the main run: also check the rules only it has to meet (``n_shards`` and
        ``fidelity`` against the run's epochs and realizations).

    Yields
    ------
    tuple of (str, object, str)
        A :data:`Problem` per broken rule: the dotted key, its value (``"…"`` when the values
        are inconsistent as a whole) and what the rule allows.  If the study's scenario
        cannot be built from ``nr``, that is the only problem, under ``root``.
    """
    from railradio.nr.engine.simulate import calibration_trajectory, scenario_from_config

    try:
        scn = scenario_from_config(dict(nr))
    except (ValueError, KeyError) as exc:
        yield root, "…", f"values the study accepts ({exc})"
        return
    n_traj = scn.trajectory.n_epochs
    n_epochs = n_traj if nr["max_epochs"] is None else min(nr["max_epochs"], n_traj)
    if main and nr["n_shards"] > n_epochs:
        yield f"{root}.n_shards", nr["n_shards"], f"<= the run's {n_epochs} epochs (one epoch per shard at least)"
    n_cal = calibration_trajectory(dict(nr)).n_epochs
    if nr["calibration"]["epochs"] > n_cal:
        yield (
            f"{root}.calibration.epochs",
            nr["calibration"]["epochs"],
            f"<= the calibration trajectory's {n_cal} epochs",
        )
    mp = nr["map"]
    for where, phases, v0 in (
        ("trajectory.phases", nr["trajectory"]["phases"], 0.0),
        (
            "calibration.trajectory.phases",
            nr["calibration"]["trajectory"]["phases"],
            nr["calibration"]["trajectory"].get("v0_m_s", 0.0),
        ),
        ("map.calibration.phases", mp["calibration"]["phases"], mp["calibration"]["v0_m_s"]),
    ):
        v = float(v0)
        for i, (dur, acc) in enumerate(phases):
            v += dur * acc
            if v < -1e-9:
                yield (
                    f"{root}.{where}[{i}]",
                    [dur, acc],
                    f"phases that keep the speed >= 0 (this one ends at {v:.3g} m/s)",
                )
    yield from _prefixed(root, _ascending(nr, "tracker.w_distance_edges_m"))
    yield from _prefixed(root, _ascending(nr, "tracker.aod_angle_edges_deg"))
    if main and nr["fidelity"]["realization"] >= nr["realizations"]:
        yield (
            f"{root}.fidelity.realization",
            nr["fidelity"]["realization"],
            f"< {root}.realizations = {nr['realizations']}",
        )
    if main and nr["fidelity"]["n_epochs"] > n_epochs:
        yield f"{root}.fidelity.n_epochs", nr["fidelity"]["n_epochs"], f"<= the run's {n_epochs} epochs"
    if main and nr["fidelity"]["n_shards"] > nr["fidelity"]["n_epochs"]:
        yield f"{root}.fidelity.n_shards", nr["fidelity"]["n_shards"], f"<= {root}.fidelity.n_epochs"
    d, d_c = nr["receiver"]["decimation"], nr["receiver"]["search_decimation"]
    d_s = nr["channel"]["synthesis_decimation"]
    if d_s > d or d % d_s:
        yield f"{root}.channel.synthesis_decimation", d_s, f"a divisor of {root}.receiver.decimation = {d}"
    if d_c > d or d % d_c:
        yield f"{root}.receiver.search_decimation", d_c, f"a divisor of {root}.receiver.decimation = {d}"
    yield from _tap_span(root, nr, scn.profile.delays_s, d)
    receivers = {"source", *nr["extra_receivers"]}
    if "source" in nr["extra_receivers"]:
        yield f"{root}.extra_receivers.source", "…", "a name other than 'source' (the source's receiver, nr.receiver)"
    if nr["imm"]["receiver"] not in receivers:
        yield (
            f"{root}.imm.receiver",
            nr["imm"]["receiver"],
            f"one of {sorted(receivers)} (source or an nr.extra_receivers name)",
        )
    dt = nr["trajectory"]["dt_s"]
    for i, tau in enumerate(nr["imm"]["sojourn_s"]):
        if tau < dt:
            yield f"{root}.imm.sojourn_s[{i}]", tau, f">= {root}.trajectory.dt_s = {dt}"


def _tap_span(root: str, nr: Mapping[str, Any], delays_s, d: int) -> Iterator[Problem]:
    """The synthesis models a delayed tap's copy of a symbol reaching at most into the next
    symbol (the taps' spill, the band's edges summed per symbol): the TDL's span within one
    normal-CP symbol, less 3 front-end samples (decimation ``d``) for the delays' rounding on
    that grid."""
    span_s = float(np.max(delays_s, initial=0.0))
    limit_s = (N_FFT + CP_NORMAL - 3 * d) / SAMPLE_RATE_HZ
    if span_s > limit_s:
        ds = nr["channel"]["delay_spread_s"]
        yield (
            f"{root}.channel.delay_spread_s",
            ds,
            f"<= {ds * limit_s / span_s:.3g} s for {nr['channel']['tdl']} "
            f"(its largest tap delay within one OFDM symbol, {limit_s * 1e6:.2f} µs)",
        )


def _prefixed(root: str, problems: Iterator[Problem]) -> Iterator[Problem]:
    for key, value, rule in problems:
        yield f"{root}.{key}", value, rule


def _nr(cfg: Mapping[str, Any], schema: Mapping[str, Any], built: dict[str, Any]) -> Iterator[Problem]:
    from railradio.nr.study import cases as nr_cases

    nr = cfg["nr"]
    yield from nr_problems(nr)
    if any(nr["sync"].values()):
        yield (
            "nr.sync",
            dict(nr["sync"]),
            ("zeros in the main run (clock errors are a sensitivity case's: nr.sensitivity.cases.<case>.sync)"),
        )
    sens = nr["sensitivity"]
    yield from _at_most(cfg, "nr.sensitivity.n_shards", "nr.sensitivity.epochs")
    n_main = main_epochs(nr)
    if n_main is not None and sens["epochs"] > n_main:
        yield (
            "nr.sensitivity.epochs",
            sens["epochs"],
            f"<= the main run's {n_main} epochs (the cases are compared with its r0 on the same epochs)",
        )
    try:
        cases = nr_cases.merged_cases(nr, schema["properties"]["nr"])
    except ConfigError as exc:
        yield "nr.sensitivity.cases", "…", str(exc).replace("invalid configuration:\n  ", "")
        return
    built["nr_cases"] = cases
    for name, case in cases.items():
        yield from nr_problems(case, root=f"nr.sensitivity.cases.{name}", main=False)
    yield from _nr_map(nr, schema, n_main, built)
    for name, sw in sens["sweeps"].items():
        key = f"nr.sensitivity.sweeps.{name}"
        bad = [c for c in sw["cases"] if c != "base" and c not in cases]
        if bad:
            yield f"{key}.cases", bad, "names of nr.sensitivity.cases (or base)"
        if len(sw["cases"]) != len(sw["values"]):
            yield f"{key}.values", sw["values"], f"one value per case ({len(sw['cases'])})"
        if sw.get("reference") is not None and sw["reference"] not in sw["cases"]:
            yield f"{key}.reference", sw["reference"], "one of the sweep's cases"


def _nr_map(
    nr: Mapping[str, Any], schema: Mapping[str, Any], n_main: int | None, built: dict[str, Any]
) -> Iterator[Problem]:
    """The reproduction map: a segment inside the main run, blocks that fit it, the main
    run's M_T among the mapped ones, every cell a valid nr config."""
    from railradio.nr.engine.simulate import calibration_trajectory
    from railradio.nr.study import reproduction_map as nr_map
    from railradio.nr.study.keys import SKIP_S

    mp = nr["map"]
    first, end = mp["segment"]
    if not first < end:
        yield "nr.map.segment", mp["segment"], "[first, end) with first < end"
        return
    if n_main is not None and end > n_main:
        yield "nr.map.segment", mp["segment"], f"an end <= the main run's {n_main} epochs (the default cell is its r0)"
    scored = end - first - int(round(SKIP_S / nr["trajectory"]["dt_s"]))
    if mp["block_epochs"] > scored:
        yield "nr.map.block_epochs", mp["block_epochs"], f"<= the segment's {scored} scored epochs"
    if mp["n_shards"] > end - first:
        yield "nr.map.n_shards", mp["n_shards"], f"<= the segment's {end - first} epochs"
    c = mp["calibration"]
    n_cal = calibration_trajectory(
        {"calibration": nr_map.calibration_section(dict(nr)), "trajectory": nr["trajectory"]}
    ).n_epochs
    if c["epochs"] > n_cal:
        yield "nr.map.calibration.epochs", c["epochs"], f"<= its trajectory's {n_cal} epochs"
    if nr["antenna"]["rrh_elements"] not in mp["rrh_elements"]:
        yield (
            "nr.map.rrh_elements",
            mp["rrh_elements"],
            f"a list holding the main run's nr.antenna.rrh_elements = {nr['antenna']['rrh_elements']} (the default "
            f"cell)",
        )
        return
    cond, bad = mp["conditions"], False
    for i, d in enumerate(cond["data"]):
        if d not in mp["data"]:
            bad = True
            yield f"nr.map.conditions.data[{i}]", d, f"one of nr.map.data: {', '.join(mp['data'])}"
    metres = [round(float(w)) for w in cond["windows_m"]]
    if len(set(metres)) < len(metres) or min(metres, default=1) < 1:
        bad = True
        yield "nr.map.conditions.windows_m", cond["windows_m"], "distinct whole metres >= 1 (each names a cell)"
    if bad:
        return
    try:
        cells = nr_map.cells(dict(nr), schema["properties"]["nr"])
    except ConfigError as exc:
        yield "nr.map.data", "…", str(exc).replace("invalid configuration:\n  ", "")
        return
    built["nr_map_cells"] = cells
    for name, cell in cells.items():
        yield from nr_problems(cell, root=f"nr.map ({name})", main=False)


def _handover(cfg: Mapping[str, Any], schema: Mapping[str, Any]) -> Iterator[Problem]:
    from railradio.config import describe_allowed
    from railradio.handover.params import scenario_from_config
    from railradio.handover.sensitivity import apply_case, cases

    ho = cfg["handover"]
    sections = schema["properties"]["handover"]["properties"]
    for switch, values in ho["sensitivity"]["switches"].items():
        section, key = switch.split(".")
        node = sections[section]["properties"][key]
        for i, v in enumerate(values):  # a switch value must be a valid value of its key
            if not Validator(node).is_valid(v):
                yield (
                    f"handover.sensitivity.switches.{switch}[{i}]",
                    v,
                    f"a value of handover.{switch}: {describe_allowed(node)}",
                )
    try:
        base = scenario_from_config(dict(ho))
    except (ValueError, KeyError):
        base = None
    if base is not None:
        for cid, case in cases(ho["sensitivity"]).items():
            yield from _probe(
                f"handover.sensitivity.switches.{case.get('switch', cid)}", lambda case=case: apply_case(base, case)
            )
    yield from _at_most(cfg, "handover.sweep.n_batches", "handover.sweep.n_blocks")
    yield from _at_most(cfg, "handover.sensitivity.n_blocks", "handover.sweep.n_blocks")
    speeds = ho["sweep"]["speeds_kmh"]
    if ho["sensitivity"]["speed_kmh"] not in speeds:
        yield (
            "handover.sensitivity.speed_kmh",
            ho["sensitivity"]["speed_kmh"],
            f"one of handover.sweep.speeds_kmh = {speeds} (the cases reuse its draws)",
        )
    yield from _at_most(cfg, "handover.cost.alpha_min", "handover.cost.alpha_max")
    yield from _at_most(
        cfg, "handover.cost.full_grid_max_m", "handover.cost.m_values", limit=max(ho["cost"]["m_values"])
    )
    yield from _ascending(cfg, "handover.joint.exponent_bounds")
    yield from _ascending(cfg, "handover.sweep.speeds_kmh")
    if ho["radio"]["q_in_db"] < ho["radio"]["q_out_db"]:
        yield (
            "handover.radio.q_in_db",
            ho["radio"]["q_in_db"],
            f">= handover.radio.q_out_db = {ho['radio']['q_out_db']} (in-sync needs the better link)",
        )
    yield from _probe("handover", lambda: scenario_from_config(dict(ho)))


def _chain(cfg: Mapping[str, Any]) -> Iterator[Problem]:
    from railradio.chain.params import params_from_config

    ch = cfg["chain"]
    yield from _at_most(cfg, "chain.n_batches", "chain.n_blocks")
    yield from _ascending(cfg, "chain.sigmas_m")
    speeds = cfg["handover"]["sweep"]["speeds_kmh"]
    if ch["speed_kmh"] not in speeds:
        yield (
            "chain.speed_kmh",
            ch["speed_kmh"],
            f"one of handover.sweep.speeds_kmh = {speeds} (the chain reuses its draws)",
        )
    yield from _probe("chain", lambda: params_from_config(dict(ch)))
    # the chain's nr input: epochs of the main run at the chain's speed
    from railradio.nr.engine.simulate import scenario_from_config

    n_main = main_epochs(cfg["nr"])
    if n_main is not None:
        traj = scenario_from_config(dict(cfg["nr"])).trajectory
        _, v, _ = traj.state(np.arange(n_main) * traj.dt_s)
        kmh = 3.6 * np.asarray(v)
        if not np.any(np.abs(kmh - ch["speed_kmh"]) <= ch["speed_halfwidth_kmh"]):
            yield (
                "chain.speed_halfwidth_kmh",
                ch["speed_halfwidth_kmh"],
                (
                    f"a window around chain.speed_kmh = {ch['speed_kmh']} that the nr run reaches (its speeds "
                    f"span {kmh.min():.0f}-{kmh.max():.0f} km/h)"
                ),
            )


def _tunnel(cfg: Mapping[str, Any]) -> Iterator[Problem]:
    from railradio.tunnel import study

    tu = cfg["tunnel"]
    g, r, m = tu["geometry"], tu["rays"], tu["measurement"]
    steps = g["slot_spacing_m"] / r["offset_step_m"]
    if abs(steps - round(steps)) > 1e-9:
        yield (
            "tunnel.rays.offset_step_m",
            r["offset_step_m"],
            f"a divisor of tunnel.geometry.slot_spacing_m = {g['slot_spacing_m']}",
        )
    if tu["coverage"]["blind_spot_dbm"] > tu["coverage"]["threshold_dbm"]:
        yield (
            "tunnel.coverage.blind_spot_dbm",
            tu["coverage"]["blind_spot_dbm"],
            f"<= tunnel.coverage.threshold_dbm = {tu['coverage']['threshold_dbm']}",
        )
    for name, t in tu["trains"].items():
        if t["length_m"] >= g["length_m"]:
            yield f"tunnel.trains.{name}.length_m", t["length_m"], f"< tunnel.geometry.length_m = {g['length_m']}"
    yield from _at_most(cfg, "tunnel.tracking.calibration_m", "tunnel.geometry.length_m")
    extent = study.table_extent_m(tu)
    if m["window_m"] > extent:
        yield (
            "tunnel.measurement.window_m",
            m["window_m"],
            f"<= the table's extent (tunnel.rays.max_offset_m) = {extent}",
        )
    if r["far_decay_m"][1] <= r["far_decay_m"][0]:
        yield "tunnel.rays.far_decay_m[1]", r["far_decay_m"][1], f"> tunnel.rays.far_decay_m[0] = {r['far_decay_m'][0]}"
    for i, off in enumerate(r["engine_offsets_m"]):
        if off > extent:
            yield (
                f"tunnel.rays.engine_offsets_m[{i}]",
                off,
                f"<= the table's extent (tunnel.rays.max_offset_m) = {extent}",
            )
    n_window = int(2 * m["window_m"] // g["slot_spacing_m"])
    if m["n_slots"] > n_window:
        yield "tunnel.measurement.n_slots", m["n_slots"], f"<= the {n_window} slots within ±tunnel.measurement.window_m"
    for shape in ("circle", "rect"):
        yield from _probe("tunnel.geometry", lambda shape=shape: study.tunnel_from_config(tu, shape))
    side_shape = study.TABLES[tu["engine"] + study.SIDE_WALL][0]  # the positioning engine's cross-section
    yield from _probe(
        "tunnel.sensitivity.side_wall_slot_z_m",
        lambda: study.tunnel_from_config(study.side_wall_config(tu), side_shape),
    )
    yield from _probe("tunnel.cable", lambda: study.cable_from_config(tu))
    yield from _probe("tunnel.measurement", lambda: study.measurement_from_config(tu))
    for name in tu["trains"]:
        yield from _probe(f"tunnel.trains.{name}", lambda name=name: study.train_from_config(tu, name))


def problems(cfg: Mapping[str, Any], schema: Mapping[str, Any], built: dict[str, Any] | None = None) -> list[Problem]:
    """Every cross-key rule ``cfg`` (schema-valid, defaults filled) breaks.

    Parameters
    ----------
    cfg : mapping
        The whole workflow config, schema-valid with the defaults filled.
    schema : mapping
        The JSON schema of the whole config (``workflow/schemas/config.schema.yaml``).
    built : dict, optional
        Receives the merged, validated nr configs the checks build, for reuse: the
        sensitivity cases under ``"nr_cases"`` and the map cells under ``"nr_map_cells"``,
        each once the checks get that far (both when no rule is broken).

    Returns
    -------
    list of tuple of (str, object, str)
        One :data:`Problem` per broken rule (dotted key, its value or ``"…"``, what the rule
        allows), by study: fusion, nr, handover, chain, tunnel; empty if none is broken.
    """
    out: list[Problem] = []
    out += _fusion(cfg)
    out += _nr(cfg, schema, {} if built is None else built)
    out += _handover(cfg, schema)
    out += _chain(cfg)
    out += _tunnel(cfg)
    return out


def check_config(cfg: Mapping[str, Any], schema: Mapping[str, Any]) -> Checked:
    """Raise :class:`ConfigError` naming each key whose value breaks a rule between keys;
    else return the nr configs the checks merged and validated.

    Parameters
    ----------
    cfg : mapping
        The whole workflow config, schema-valid with the defaults filled.
    schema : mapping
        The JSON schema of the whole config (``workflow/schemas/config.schema.yaml``).

    Returns
    -------
    Checked
        The nr sensitivity cases and map cells, each merged with the nr section and
        validated (once): the workflow's nr plan reuses them.

    Raises
    ------
    railradio.config.ConfigError
        If any rule of :func:`problems` is broken; the message lists every broken rule with
        its key, value and what is allowed.
    """
    built: dict[str, Any] = {}
    found = problems(cfg, schema, built)
    if found:
        lines = [
            f"config key '{k}': "
            + ("the values are inconsistent" if v == "…" else f"{v!r} is not allowed")
            + f". Allowed: {rule}."
            for k, v, rule in found
        ]
        raise ConfigError("invalid configuration:\n  " + "\n  ".join(lines))
    return Checked(nr_cases=built["nr_cases"], nr_map_cells=built["nr_map_cells"])
