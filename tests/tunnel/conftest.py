"""Fixtures of the tunnel tests: the CI-scale tunnel config and its image-method table."""

import pytest
import yaml

from railradio.config import deep_merge
from railradio.tunnel.study import make_order, make_table


@pytest.fixture(scope="module")
def ci():
    with open("config/config.yaml") as f:
        base = yaml.safe_load(f)
    with open("config/ci.yaml") as f:
        over = yaml.safe_load(f)
    cfg = deep_merge(base, over)["tunnel"]
    return cfg, make_table(cfg, "image", 7, make_order(cfg))
