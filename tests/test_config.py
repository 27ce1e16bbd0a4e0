import copy

import pytest
import yaml

from railradio.config import ConfigError, load_schema, validate_config

from .conftest import ROOT

SCHEMA = load_schema(ROOT / "workflow/schemas/config.schema.yaml")


def _paper():
    with open(ROOT / "config/config.yaml") as fh:
        return yaml.safe_load(fh)


def test_paper_and_ci_configs_are_valid():
    validate_config(_paper(), SCHEMA)
    cfg = _paper()
    with open(ROOT / "config/ci.yaml") as fh:
        ci = yaml.safe_load(fh)
    from railradio.config import deep_merge

    validate_config(deep_merge(cfg, ci), SCHEMA)  # Snakemake merges --configfile recursively


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
        (("nr", "sensitivity", "tracker_variants"), ["aod", "toa"],
         ["nr.sensitivity.tracker_variants", "aod_toa"]),
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
