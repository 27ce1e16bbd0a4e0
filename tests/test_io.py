import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from railradio import __version__
from railradio.io import PROVENANCE_ATTRS, atomic_path, config_of, read_dataset, write_dataset


def _ds():
    return xr.Dataset(
        {
            "err": (("t",), np.array([1.0, -2.5, 3.25]), {"units": "m", "long_name": "error"}),
            "iq": (("t",), np.array([1 + 2j, -3j, 0.5]), {"units": "V", "long_name": "sample"}),
        },
        coords={"t": ("t", [0.0, 0.1, 0.2], {"units": "s", "long_name": "time"})},
    )


def test_round_trip_keeps_values_units_and_provenance(tmp_path):
    cfg = {"b": 2, "a": [1.5]}
    path = tmp_path / "sub" / "x.nc"
    write_dataset(_ds(), path, cfg, (2, 7, 9), title="test")
    back = read_dataset(path)
    xr.testing.assert_allclose(back[["err", "iq"]], _ds()[["err", "iq"]])
    assert back["iq"].dtype.kind == "c"
    assert back["err"].attrs["units"] == "m" and back["iq"].attrs["long_name"] == "sample"
    assert back["t"].attrs["units"] == "s"
    for attr in PROVENANCE_ATTRS:
        assert attr in back.attrs
    assert config_of(back) == cfg
    assert json.loads(back.attrs["seed_spawn_key"]) == [2, 7, 9]
    assert back.attrs["railradio_version"] == __version__
    # plain xarray sees the portable real/imag split with units
    with xr.open_dataset(path) as raw:
        assert raw["iq_real"].attrs["units"] == "V" and "iq" not in raw


def test_missing_units_rejected(tmp_path):
    ds = _ds()
    del ds["err"].attrs["units"]
    with pytest.raises(ValueError, match="err"):
        write_dataset(ds, tmp_path / "x.nc", {}, None, title="t")
    assert not any(tmp_path.iterdir())


def test_atomic_path_leaves_nothing_on_interrupt(tmp_path):
    target = tmp_path / "out.nc"
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(target) as tmp:
            Path(tmp).write_text("half")
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_atomic_path_replaces_old_file_only_on_success(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("new")
            raise RuntimeError
    assert target.read_text() == "old"
    with atomic_path(target) as tmp:
        tmp.write_text("new")
    assert target.read_text() == "new"
