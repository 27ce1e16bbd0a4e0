"""The schema rejects bad tunnel config values, naming the key and the range."""

import copy

import pytest
import yaml

from railradio.config import ConfigError, load_schema, validate_config

from ..conftest import ROOT

SCHEMA = load_schema(ROOT / "workflow/schemas/config.schema.yaml")


def _paper():
    with open(ROOT / "config/config.yaml") as fh:
        return yaml.safe_load(fh)


@pytest.mark.parametrize(
    ("path", "value", "must_mention"),
    [
        (("tunnel", "cable", "velocity_factor"), 1.5, ["tunnel.cable.velocity_factor", "<= 1"]),
        (("tunnel", "rays", "sbr_polarization"), "circular", ["tunnel.rays.sbr_polarization", "vector"]),
        (("tunnel", "trains", "hst", "length_m"), -200.0, ["tunnel.trains.hst.length_m", ">= 10"]),
        (("tunnel", "measurement", "n_slots"), 2, ["tunnel.measurement.n_slots", ">= 3"]),
        (("tunnel", "sensitivity", "side_wall_slot_z_m"), 12.0, ["tunnel.sensitivity.side_wall_slot_z_m", "<= 10"]),
    ],
)
def test_bad_tunnel_values_rejected(path, value, must_mention):
    cfg = copy.deepcopy(_paper())
    node = cfg
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    with pytest.raises(ConfigError) as exc:
        validate_config(cfg, SCHEMA)
    for text in must_mention:
        assert text in str(exc.value)


def test_ci_tunnel_overrides_valid():
    cfg = _paper()
    with open(ROOT / "config/ci.yaml") as fh:
        ci = yaml.safe_load(fh)
    from railradio.config import deep_merge

    validate_config(deep_merge(cfg, {"tunnel": ci["tunnel"]}), SCHEMA)  # Snakemake merges recursively


def test_side_wall_case_moves_only_the_slot_line():
    """The side-wall tables get the slot line at side_wall_slot_z_m, inside the square's wall
    (and farther from the roof antenna); the other tables' config is unchanged; a position
    outside the cross-section is refused naming the slot."""
    from railradio.tunnel.study import channel_config, side_wall_config, tunnel_from_config

    cfg = _paper()["tunnel"]
    keys = ["geometry", "cable"]
    assert channel_config(cfg, "image", keys)["geometry"] == cfg["geometry"]
    sw = channel_config(cfg, "image_side_wall", keys)
    assert sw["geometry"]["slot_z_m"] == cfg["sensitivity"]["side_wall_slot_z_m"]
    assert {k: v for k, v in sw["geometry"].items() if k != "slot_z_m"} == {
        k: v for k, v in cfg["geometry"].items() if k != "slot_z_m"
    }
    centre, side = tunnel_from_config(cfg, "rect"), tunnel_from_config(side_wall_config(cfg), "rect")
    assert 0.05 <= side.wall_distance_m(*side.slot_yz) < 0.5
    assert side.cross_distance_m > centre.cross_distance_m
    with pytest.raises(ValueError, match="slot position"):
        tunnel_from_config(side_wall_config(cfg), "circle")  # 3.6 m lies outside the circle at 0.85 m height
