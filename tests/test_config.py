"""Config validation: the schema (types, ranges, a default for every key) and the rules
between keys (railradio.config_checks), one test per kind of bad value; all in process."""

import copy

import pytest
import yaml

from railradio.config import ConfigError, deep_merge, load_schema, validate_config
from railradio.config_checks import check_config

from .conftest import ROOT

SCHEMA = load_schema(ROOT / "workflow/schemas/config.schema.yaml")


def _yaml(path):
    with open(path) as fh:
        return yaml.safe_load(fh)


def _paper():
    return _yaml(ROOT / "config/config.yaml")


def _ci():
    return deep_merge(_paper(), _yaml(ROOT / "config/ci.yaml"))


def _with(cfg, dotted, value):
    """Set a key given as "a.b.c" (or as a tuple of parts, for a key that holds a dot)."""
    node = cfg
    parts = list(dotted) if isinstance(dotted, tuple) else dotted.split(".")
    for p in parts[:-1]:
        node = node[p]
    node[parts[-1]] = value
    return cfg


def _full_check(cfg):
    validate_config(cfg, SCHEMA)
    check_config(cfg, SCHEMA)


def test_an_empty_config_is_the_paper_scale():
    """Every key has a schema default, and the defaults are config/config.yaml."""
    assert validate_config({}, SCHEMA) == _paper()


def _leaves(node, key=""):
    if node.get("type") == "object" and "properties" in node:
        for name, sub in node["properties"].items():
            yield from _leaves(sub, f"{key}.{name}" if key else name)
    else:
        yield key, node


def test_every_key_has_a_default_and_a_description():
    missing = [k for k, n in _leaves(SCHEMA) if "default" not in n]
    assert not missing, missing
    undocumented = [k for k, n in _leaves(SCHEMA) if not n.get("description")]
    assert not undocumented, undocumented
    assert len(list(_leaves(SCHEMA))) > 200


def test_every_array_bounds_its_length_or_says_why_empty_is_meaningful():
    """An array without minItems must be one whose empty value means something (stated in
    its description): the distance bins of W (one W), the AOD model's angle bins (the
    source's unbiased W), the conditions' search windows (the source's K alone) and the
    handover switches (not varied)."""

    def arrays(node, key=""):
        if "array" in ([node.get("type")] if isinstance(node.get("type"), str) else node.get("type", [])):
            yield key, node
        for name, sub in (node.get("properties") or {}).items():
            yield from arrays(sub, f"{key}.{name}" if key else name)

    free = sorted(k for k, n in arrays(SCHEMA) if "minItems" not in n)
    empty_means = {"nr.tracker.w_distance_edges_m", "nr.tracker.aod_angle_edges_deg", "nr.map.conditions.windows_m"}
    assert all(k in empty_means or k.startswith("handover.sensitivity.switches.") for k in free), free


def test_shipped_configs_pass_every_rule():
    _full_check(_paper())
    _full_check(_ci())  # Snakemake merges --configfile recursively
    _full_check(deep_merge(_paper(), _yaml(ROOT / "workflow/profiles/slurm/shards.yaml")))


def test_defaults_filled():
    cfg = _paper()
    del cfg["fusion"]["clip"]
    validate_config(cfg, SCHEMA)
    assert cfg["fusion"]["clip"] == "no_solution"


@pytest.mark.parametrize(
    ("path", "value", "must_mention"),
    [
        (("fusion", "reference", "sigma_aoa_rad"), -0.01, ["fusion.reference.sigma_aoa_rad", "> 0"]),
        (("fusion", "sweeps", "d_m"), [], ["fusion.sweeps.d_m", "at least 1"]),
        (("fusion", "n_trials"), "many", ["fusion.n_trials", "integer", ">= 2"]),
        (("fusion", "clip"), "sometimes", ["fusion.clip", "no_solution"]),
        (("seed",), -3, ["seed", ">= 0"]),
        (("nr", "sensitivity", "measurement_sets"), ["aod", "toa"], ["nr.sensitivity.measurement_sets", "aod_toa"]),
    ],
)
def test_bad_values_name_key_and_range(path, value, must_mention):
    cfg = copy.deepcopy(_paper())
    node = cfg
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    with pytest.raises(ConfigError) as exc:
        validate_config(cfg, SCHEMA)
    for text in must_mention:
        assert text in str(exc.value)


def test_unknown_key_rejected():
    cfg = _paper()
    cfg["fusion"]["n_trail"] = 3
    with pytest.raises(ConfigError, match="n_trail"):
        validate_config(cfg, SCHEMA)


def test_deep_merge_and_prefixed_messages():
    from railradio.config import deep_merge

    base = {"a": {"b": 1, "c": [1, 2]}, "d": 2}
    merged = deep_merge(base, {"a": {"b": 5}, "e": 3})
    assert merged == {"a": {"b": 5, "c": [1, 2]}, "d": 2, "e": 3}
    assert base == {"a": {"b": 1, "c": [1, 2]}, "d": 2}  # untouched
    nr = deep_merge(_paper()["nr"], {"traffic": {"data_beam": "sideways"}})
    with pytest.raises(ConfigError) as exc:
        validate_config(nr, SCHEMA["properties"]["nr"], root="nr.sensitivity.cases.x")
    assert "nr.sensitivity.cases.x.traffic.data_beam" in str(exc.value)
    assert "'train'" in str(exc.value)


@pytest.mark.parametrize(
    ("dotted", "value", "must_mention"),
    [  # one per kind of bad value the schema catches
        ("seed", 10.0, ["'seed'", "integer"]),  # an integer written as a float
        ("nr.n_shards", True, ["nr.n_shards", "integer"]),  # a boolean is no count
        ("nr.trajectory.phases", [[-20.0, 0.5]], ["nr.trajectory.phases[0][0]", "> 0"]),  # a negative duration
        ("tunnel.sensitivity.delay_sigma_ns", [], ["tunnel.sensitivity.delay_sigma_ns", "at least 1"]),
        ("nr.tracker.q_grid", [1.0, 1.0], ["nr.tracker.q_grid", "no repeated items"]),
        ("nr.radio.carrier_hz", "3e10", ["nr.radio.carrier_hz", "number"]),  # a string where a number belongs
        ("nr.max_epochs", 10**9, ["nr.max_epochs", "<= 1000000"]),
    ],
)
def test_schema_rejects_each_kind_of_bad_value(dotted, value, must_mention):
    with pytest.raises(ConfigError) as exc:
        validate_config(_with(_paper(), dotted, value), SCHEMA)
    for text in must_mention:
        assert text in str(exc.value), str(exc.value)


@pytest.mark.parametrize(
    ("dotted", "value", "must_mention"),
    [  # the values and keys renamed in config/README.md "Migration": the old spelling is refused
        ("nr.receiver.ssb_pattern", "seed", ["nr.receiver.ssb_pattern", "'source'"]),
        ("nr.receiver.detector", "seed", ["nr.receiver.detector", "'source'"]),
        ("nr.cell_search.detector", "seed", ["nr.cell_search.detector", "'source'"]),
        ("nr.extra_receivers.robust.detector", "seed", ["nr.extra_receivers.robust.detector", "'source'"]),
        ("tunnel.seed_model", {"reflection_loss_db": 8.0}, ["config key 'tunnel'", "'seed_model' was unexpected"]),
        ("nr.receiver_variants", {}, ["config key 'nr'", "'receiver_variants' was unexpected"]),
        (
            "nr.sensitivity.tracker_variants",
            ["aod_toa"],
            ["config key 'nr.sensitivity'", "'tracker_variants' was unexpected"],
        ),
        ("handover.joint.gaph_variant", "narrow", ["config key 'handover.joint'", "'gaph_variant' was unexpected"]),
        (
            ("handover", "sensitivity", "switches", "joint.gaph_variant"),
            ["narrow"],
            ["config key 'handover.sensitivity.switches'", "'joint.gaph_variant' was unexpected"],
        ),
    ],
)
def test_schema_rejects_renamed_values(dotted, value, must_mention):
    with pytest.raises(ConfigError) as exc:
        validate_config(_with(_paper(), dotted, value), SCHEMA)
    for text in must_mention:
        assert text in str(exc.value), str(exc.value)


@pytest.mark.parametrize(
    ("changes", "must_mention"),
    [  # one per kind of rule between keys
        ({"handover.sweep.n_batches": 3}, ["handover.sweep.n_batches", "<= handover.sweep.n_blocks = 2"]),
        ({"chain.n_batches": 3}, ["chain.n_batches", "<= chain.n_blocks = 2"]),
        ({"nr.n_shards": 500}, ["nr.n_shards", "160 epochs"]),  # shards <= epochs (CI: 160)
        ({"nr.sensitivity.n_shards": 100}, ["nr.sensitivity.n_shards", "<= nr.sensitivity.epochs = 60"]),
        ({"nr.calibration.epochs": 100000}, ["nr.calibration.epochs", "trajectory"]),
        (
            {"nr.calibration.trajectory.phases": [[10.0, 1.0], [20.0, -1.0]]},
            ["nr.calibration.trajectory.phases[1]", "speed >= 0"],
        ),
        ({"chain.sigmas_m": [0.0, 20.0, 2.0]}, ["chain.sigmas_m", "ascending"]),
        ({"nr.tracker.w_distance_edges_m": [750.0, 250.0]}, ["nr.tracker.w_distance_edges_m", "ascending"]),
        ({"nr.imm.receiver": "fancy"}, ["nr.imm.receiver", "robust"]),  # a name that does not exist
        ({"nr.imm.receiver": "seed"}, ["nr.imm.receiver", "'source'"]),  # the source's receiver's old name
        ({"nr.imm.sojourn_s": [100.0, 0.01]}, ["nr.imm.sojourn_s[1]", "dt_s"]),
        ({"handover.sensitivity.speed_kmh": 123}, ["handover.sensitivity.speed_kmh", "speeds_kmh"]),
        ({"chain.speed_kmh": 123}, ["chain.speed_kmh", "speeds_kmh"]),
        ({"handover.radio.q_in_db": -9.0}, ["handover.radio.q_in_db", "q_out_db"]),
        ({"handover.cost.alpha_min": 0.95}, ["handover.cost.alpha_min", "alpha_max"]),
        ({"nr.trajectory.phases": [[100.0, 0.5], [200.0, -0.5]]}, ["nr.trajectory.phases[1]", "speed"]),
        ({"nr.sync": {"rrh_sigma_s": 1e-9, "train_bias_s": 0.0}}, ["nr.sync", "main run"]),
        (
            {"nr.sensitivity.sweeps": {"s": {"label": "x", "cases": ["nope"], "values": [1]}}},
            ["nr.sensitivity.sweeps.s.cases", "nr.sensitivity.cases"],
        ),
        (
            {"nr.sensitivity.sweeps": {"s": {"label": "x", "cases": ["base"], "values": [1, 2]}}},
            ["nr.sensitivity.sweeps.s.values", "one value per case"],
        ),
        (
            {"nr.sensitivity.cases": {"loud": {"radio": {"tx_power_dbm": 900}}}},
            ["nr.sensitivity.cases.loud.radio.tx_power_dbm", "<= 80"],
        ),
        (
            {"nr.sensitivity.cases": {"far": {"n_shards": 1, "calibration": {"epochs": 10**5}}}},
            ["nr.sensitivity.cases.far.calibration.epochs"],
        ),
        ({"tunnel.rays.offset_step_m": 0.3}, ["tunnel.rays.offset_step_m", "slot_spacing_m"]),
        ({"tunnel.trains.freight.length_m": 1500.0}, ["tunnel.trains.freight.length_m", "length_m = 1200"]),
        ({"tunnel.geometry.rx_y_m": 9.0}, ["tunnel.geometry", "outside"]),  # a study's own check
        ({"tunnel.sensitivity.side_wall_slot_z_m": 6.0}, ["tunnel.sensitivity.side_wall_slot_z_m", "outside"]),
        ({"fusion.sensitivity.radii_m": [1000.0]}, ["fusion.sensitivity.radii_m[0]", "d_m"]),
        ({"nr.sensitivity.epochs": 500}, ["nr.sensitivity.epochs", "main run's 160 epochs"]),
        ({"chain.speed_halfwidth_kmh": 10.0}, ["chain.speed_halfwidth_kmh", "reaches"]),  # CI: 0-57 km/h
        (
            {"nr.channel.delay_spread_s": 1e-6},
            ["nr.channel.delay_spread_s", "within one OFDM symbol"],
        ),  # TDL-D: 12.5 µs
        (
            {"nr.sensitivity.cases": {"long": {"channel": {"tdl": "TDL-A", "delay_spread_s": 5e-7}}}},
            ["nr.sensitivity.cases.long.channel.delay_spread_s", "TDL-A"],
        ),
        (
            {("handover", "sensitivity", "switches", "radio.spacing_m"): [10.0]},
            ["handover.sensitivity.switches.radio.spacing_m[0]", ">= 500"],
        ),
        (
            {("handover", "sensitivity", "switches", "a3.ttt_s"): [0.33]},  # not a TS 36.331 TimeToTrigger
            ["handover.sensitivity.switches.a3.ttt_s[0]", "0.32"],
        ),
    ],
)
def test_rules_between_keys_name_the_key(changes, must_mention):
    cfg = _ci()
    for dotted, value in changes.items():
        _with(cfg, dotted, value)
    with pytest.raises(ConfigError) as exc:
        _full_check(cfg)
    msg = str(exc.value)
    for text in must_mention:
        assert text in msg, msg
    assert "Allowed:" in msg


def test_every_broken_rule_is_reported_at_once():
    cfg = _with(_with(_ci(), "handover.sweep.n_batches", 3), "chain.n_batches", 3)
    with pytest.raises(ConfigError) as exc:
        _full_check(cfg)
    assert "handover.sweep.n_batches" in str(exc.value) and "chain.n_batches" in str(exc.value)
