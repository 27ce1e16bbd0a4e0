"""Our detector's constants one at a time and every receiver's false alarms on noise-only
bursts, measured beside the fidelity target (:mod:`railradio.nr.study.fidelity`) on its epochs."""

from __future__ import annotations

import dataclasses

import numpy as np

from railradio.nr.engine.simulate import Scenario
from railradio.nr.receiver.correlator import CA_GUARD_FULL, CA_WINDOW_FULL
from railradio.nr.receiver.frontend import upsample
from railradio.nr.study.fidelity_receivers import Receivers
from railradio.nr.synthesis.synthesizer import Synthesizer

DETECTOR_SETTINGS = {
    "ca_window": (256, 1024),  # full-rate lags on each side (the default CA_WINDOW_FULL: 512)
    "ca_guard": (16, 64),  # full-rate guard lags (default CA_GUARD_FULL: 32)
    "ca_prescreen": (0.6, 0.9),  # share of the threshold (default CA_PRESCREEN: 0.8)
    "toa_blocks": (1, 2, 4, 6, 0),  # the most significant detected blocks combined (0: all; default nr.extra_receivers)
}
"""One-at-a-time settings of our receiver's detector constants around the defaults."""


def detector_setting_receivers(scn: Scenario, name: str = "robust") -> dict[str, tuple]:
    """{label: (ReceiverConfig, detector, Correlator kwargs, attribute overrides)} for the
    settings of :data:`DETECTOR_SETTINGS` applied to the receiver ``name`` of ``scn.extra_receivers``.

    Parameters
    ----------
    scn : Scenario
        The scenario (its ``extra_receivers`` and correlation decimation).
    name : str
        The extra receiver whose detector constants are varied.

    Returns
    -------
    dict of str to tuple
        ``"<setting>_<value>"`` -> (ReceiverConfig, detector, kwargs of
        :class:`railradio.nr.receiver.correlator.Correlator` (``ca_window``, ``ca_guard`` [lags at F_s/D_c]),
        attributes to set on the correlator (``ca_prescreen``)).

    Raises
    ------
    StopIteration
        When ``scn.extra_receivers`` has no receiver ``name``.
    """
    rc, det = next((rc, det) for n, rc, det in scn.extra_receivers if n == name)
    d_c = scn.search_decimation or scn.receiver.decimation
    out = {}
    for key, values in DETECTOR_SETTINGS.items():
        for v in values:
            kw, attrs, cfg = {}, {}, rc
            if key == "ca_window":
                kw["ca_window"] = v // d_c
            elif key == "ca_guard":
                kw["ca_guard"] = v // d_c
            elif key == "ca_prescreen":
                attrs["ca_prescreen"] = v
            else:
                cfg = dataclasses.replace(rc, toa_blocks=None if v == 0 else v)
            out[f"{key}_{v}"] = (cfg, det, kw, attrs)
    assert CA_WINDOW_FULL not in DETECTOR_SETTINGS["ca_window"] and CA_GUARD_FULL not in DETECTOR_SETTINGS["ca_guard"]
    return out


NOISE_ONLY_ID = 2000
"""Realization ID of the noise-only bursts' generator (the main run's are 0, 1, …; the
calibration run's 1000)."""


def noise_false_alarms(
    scn: Scenario, n_bursts: int, rng: np.random.Generator, n_cells: int = 6
) -> dict[str, tuple[int, int]]:
    """False alarms of every receiver on noise-only bursts: ``{receiver: (detections,
    block tests)}``. Each burst is complex white noise at the front end's rate over the
    production burst's unpadded length (white noise: its period does not matter), tested for
    ``n_cells`` cells drawn from the deployment.

    Parameters
    ----------
    scn : Scenario
        The scenario (receivers, deployment, decimation).
    n_bursts : int
        Noise-only bursts.
    rng : numpy.random.Generator
        Generator of the noise and the cells (keyed by :data:`NOISE_ONLY_ID`).
    n_cells : int
        Cells tested per burst (at most the deployment's).

    Returns
    -------
    dict of str to tuple of (int, int)
        Receiver -> (detections, block tests).
    """
    rx = Receivers(
        scn,
        {n: "peak" for n, _, _ in [("source", None, None)] + list(scn.extra_receivers)},
        scn.search_decimation or scn.receiver.decimation,
    )
    d = scn.receiver.decimation
    fast = Synthesizer(scn.receiver, scn.profile, np.zeros((1, 1024), np.complex64))
    sp = fast.span(0.0)
    n1_all, n2_all = scn.deployment.n_id()
    counts = {name: [0, 0] for name in rx.names}
    for _ in range(n_bursts):
        z = ((rng.standard_normal(sp["total"]) + 1j * rng.standard_normal(sp["total"])) / np.sqrt(2)).astype(
            np.complex64
        )
        cells = rng.choice(n1_all.size, size=n_cells, replace=False)
        out = rx(upsample(z, d // rx.decimation), sp["s_min"], n1_all[cells], n2_all[cells])
        for name, dec in out.items():
            counts[name][0] += int(dec.detected.sum())
            counts[name][1] += int(dec.detected.size)
    return {k: (v[0], v[1]) for k, v in counts.items()}
