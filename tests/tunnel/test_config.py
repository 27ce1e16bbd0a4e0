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


@pytest.mark.parametrize(("path", "value", "must_mention"), [
    (("tunnel", "cable", "velocity_factor"), 1.5, ["tunnel.cable.velocity_factor", "<= 1"]),
    (("tunnel", "rays", "sbr_polarization"), "circular", ["tunnel.rays.sbr_polarization", "vector"]),
    (("tunnel", "trains", "hst", "length_m"), -200.0, ["tunnel.trains.hst.length_m", ">= 10"]),
    (("tunnel", "measurement", "n_slots"), 2, ["tunnel.measurement.n_slots", ">= 3"]),
])
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
