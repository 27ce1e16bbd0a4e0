"""The train-length (attitude) key: the estimated head-tail extent against the true length."""

import numpy as np
import xarray as xr

from railradio.tunnel.keys import length_error_m


def test_length_error_from_head_and_tail_estimates():
    ds = xr.Dataset(
        {"kf_head": ("t", np.array([200.0, 201.0, 199.5])), "kf_tail": ("t", np.array([0.0, 0.5, 0.5]))},
        attrs={"length_m": 200.0},
    )
    np.testing.assert_allclose(length_error_m(ds), [0.0, 0.5, 1.0])
