"""The per-epoch record of :func:`railradio.nr.engine.epochs.simulate_epochs` and the estimates
dataset built from it (``results/nr/estimates/{real}/s{shard}.nc``): the reported epochs'
truth, for scoring, beside every receiver's estimates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S

if TYPE_CHECKING:
    from railradio.nr.channel.geometry import Deployment
    from railradio.nr.engine.simulate import Burst, EpochEstimates, Scenario


_CD = ("epoch", "cand")
_RD = ("receiver", "epoch", "cand")


@dataclass
class EpochRecord:
    """The reported epochs' truth and estimates of :func:`simulate_epochs`, filled epoch by
    epoch: ``truth`` (x, v, a, sir) [epoch], ``out`` (per candidate) [epoch, cand], ``meas``
    (per receiver and candidate) [receiver, epoch, cand]."""

    truth: dict[str, np.ndarray]
    serving: np.ndarray
    out: dict[str, np.ndarray]
    meas: dict[str, np.ndarray]
    acquired: np.ndarray
    corr_keep: dict = field(default_factory=dict)

    @classmethod
    def empty(cls, n_r: int, n_e: int, n_c: int) -> EpochRecord:
        """Arrays for ``n_r`` receivers, ``n_e`` epochs and ``n_c`` candidates (NaN, or 0 and -1
        for the integers).

        Parameters
        ----------
        n_r, n_e, n_c : int
            Receivers, reported epochs and candidates per epoch.

        Returns
        -------
        EpochRecord
            ``truth`` [n_e] (``x``, ``v``, ``a``, ``sir``: NaN), ``serving`` [n_e] (-1),
            ``out`` [n_e, n_c] (``rrh``, ``panel``: 0; the rest NaN), ``meas`` [n_r, n_e, n_c]
            (``n_detected``: 0; the rest NaN), ``acquired`` [n_e] (False).
        """
        truth = {name: np.full(n_e, np.nan) for name in ("x", "v", "a", "sir")}
        serving = np.full(n_e, -1, dtype=np.int64)
        out = {name: np.full((n_e, n_c), np.nan) for name in ("d3d_m", "aod_true_rad", "rx_power_dbm", "ss_rsrp")}
        meas = {name: np.full((n_r, n_e, n_c), np.nan) for name in ("aod_rad", "toa_s", "peak", "best_score")}
        out["rrh"] = np.zeros((n_e, n_c), dtype=np.int64)
        out["panel"] = np.zeros((n_e, n_c), dtype=np.int64)
        meas["n_detected"] = np.zeros((n_r, n_e, n_c), dtype=np.int64)
        acquired = np.zeros(n_e, dtype=bool)
        return cls(truth, serving, out, meas, acquired)

    def record(self, i: int, e: int, b: Burst, m: EpochEstimates, dep: Deployment) -> None:
        """Store epoch ``e`` (the ``i``-th reported): the estimates ``m`` and, for scoring, the
        truth of the burst ``b``.

        Parameters
        ----------
        i : int
            Row of the epoch in the record, in ``0..n_e - 1``.
        e : int
            Epoch index (the key of a kept correlation).
        b : Burst
            The epoch's burst and truth (position [m], speed [m/s], acceleration [m/s²], link budget).
        m : EpochEstimates
            The receiver's measurements at the epoch.
        dep : Deployment
            The deployment (geometry of candidates out of radio range).
        """
        truth, serving, out, meas, acquired = self.truth, self.serving, self.out, self.meas, self.acquired
        n_c = out["rrh"].shape[1]
        cand = m.cand
        out["rrh"][i], acquired[i], out["ss_rsrp"][i] = cand, m.acquired, m.ss_rsrp_db
        for name in meas:
            meas[name][:, i] = getattr(m, name)
        if m.corr is not None:
            self.corr_keep[e] = (m.corr, cand)
        # truth, for scoring: a candidate beyond radio.range_m (sparse RRHs near the
        # track's ends) sends nothing: its truth is the geometry to the reference point,
        # its received power NaN, and a detection of it a false alarm
        lb = b.links
        truth["x"][i], truth["v"][i], truth["a"][i], serving[i] = b.x_m, b.v_m_s, b.a_m_s2, b.serving
        inr = np.isin(cand, lb.rrh)
        pos = np.searchsorted(lb.rrh, cand[inr])
        out["d3d_m"][i] = dep.distance_3d_m(np.full(n_c, b.x_m), cand)
        out["aod_true_rad"][i] = dep.aod_rad(np.full(n_c, b.x_m), cand)
        out["d3d_m"][i, inr] = lb.d3d_m[pos]
        out["aod_true_rad"][i, inr] = lb.aod_rad[pos]
        out["rx_power_dbm"][i, inr] = lb.rx_power_dbm[pos]
        if lb.panel is not None:
            out["panel"][i, inr] = lb.panel[pos]
        p_all = 10 ** (lb.rx_power_dbm / 10)
        truth["sir"][i] = 10 * np.log10(p_all.max() / (p_all.sum() - p_all.max()))


def estimates_dataset(scn: Scenario, epochs: np.ndarray, receivers: list[str], rec: EpochRecord) -> xr.Dataset:
    """:func:`simulate_epochs`'s dataset from the record of its epochs.

    Parameters
    ----------
    scn : Scenario
        The scenario (trajectory ``dt_s``, train panels).
    epochs : numpy.ndarray of int
        The reported epoch indices, [n_e].
    receivers : list of str
        Receiver names, in the order of the record's first axis.
    rec : EpochRecord
        The filled record.

    Returns
    -------
    xarray.Dataset
        Dims ``epoch``, ``cand``, ``receiver``, ``panel_id`` (and ``block``, ``lag`` for a kept
        correlation); the variables and their units are those of
        :func:`railradio.nr.engine.epochs.simulate_epochs`.
    """
    n_c = rec.out["rrh"].shape[1]
    ds = xr.Dataset(
        _train_vars(scn, epochs, rec)
        | _cell_search_vars(rec)
        | _candidate_truth_vars(scn, rec)
        | _estimate_vars(rec)
        | {
            "sir_best": (
                ("epoch",),
                rec.truth["sir"],
                {"units": "dB", "long_name": "true strongest RRH power over the sum of the others"},
            )
        },
        coords={
            "epoch": ("epoch", epochs, {"units": "1", "long_name": "measurement epoch index (dt apart)"}),
            "cand": (
                "cand",
                np.arange(n_c),
                {"units": "1", "long_name": "place in the neighbour list (0: the anchor cell)"},
            ),
            "receiver": ("receiver", receivers, {"units": "1", "long_name": "receiver"}),
            "panel_id": ("panel_id", [0, 1], {"units": "1", "long_name": "train panel: 0 head, 1 tail"}),
        },
    )
    if rec.corr_keep:
        e0 = sorted(rec.corr_keep)[0]
        corr, cand = rec.corr_keep[e0]
        ds["corr_sample"] = (
            ("cand", "block", "lag"),
            corr,
            {"units": "1", "long_name": f"|r_i[k]| of epoch {e0} (decimated lags)"},
        )
        ds["corr_sample_epoch"] = ((), e0, {"units": "1", "long_name": "epoch of corr_sample"})
    return ds


def _train_vars(scn: Scenario, epochs: np.ndarray, rec: EpochRecord) -> dict:
    """The epochs' times and the train's true state and serving cell."""
    t = epochs * scn.trajectory.dt_s
    return {
        "t": (("epoch",), t, {"units": "s", "long_name": "time of the burst start (truth instant)"}),
        "x_true": (("epoch",), rec.truth["x"], {"units": "m", "long_name": "true train position along the track"}),
        "v_true": (("epoch",), rec.truth["v"], {"units": "m s-1", "long_name": "true train speed"}),
        "a_true": (("epoch",), rec.truth["a"], {"units": "m s-2", "long_name": "true train acceleration"}),
        "serving_true": (
            ("epoch",),
            rec.serving,
            {"units": "1", "long_name": "the network's serving RRH (truth; -1: none in range)"},
        ),
    }


def _cell_search_vars(rec: EpochRecord) -> dict:
    """The cell search's candidate lists, acquisitions and SS-RSRP."""
    return {
        "rrh": (
            _CD,
            rec.out["rrh"],
            {"units": "1", "long_name": "candidate RRH index: the cell search's neighbour list, its anchor cell first"},
        ),
        "acquired": (
            ("epoch",),
            rec.acquired,
            {"units": "1", "long_name": "a blind acquisition (every PCI searched) ran at this epoch"},
        ),
        "ss_rsrp": (
            _CD,
            rec.out["ss_rsrp"],
            {
                "units": "dB",
                "long_name": (
                    "SS-RSRP of the cell search (SSS despread, best detected block; arbitrary reference "
                    "common to all cells), NaN if not detected"
                ),
            },
        ),
    }


def _candidate_truth_vars(scn: Scenario, rec: EpochRecord) -> dict:
    """Each candidate's truth (for scoring) and the train's panels."""
    return {
        "d3d": (_CD, rec.out["d3d_m"], {"units": "m", "long_name": "true 3-D train-RRH distance"}),
        "toa_true": (_CD, rec.out["d3d_m"] / SPEED_OF_LIGHT_M_S, {"units": "s", "long_name": "true propagation delay"}),
        "aod_true": (
            _CD,
            rec.out["aod_true_rad"],
            {"units": "rad", "long_name": "true azimuth of departure at the RRH"},
        ),
        "rx_power": (
            _CD,
            rec.out["rx_power_dbm"],
            {"units": "dBm", "long_name": "true received power with the best beam"},
        ),
        "panel": (
            _CD,
            rec.out["panel"],
            {
                "units": "1",
                "long_name": (
                    "train panel receiving the RRH more strongly (0 head, 1 tail); distance, delay and angles are to it"
                ),
            },
        ),
        "train_panel_x": (
            ("panel_id",),
            np.asarray(scn.train_array.panel_x_m, float),
            {
                "units": "m",
                "long_name": (
                    "along-track position of the head (0) and tail (1) panels from the train's reference point"
                ),
            },
        ),
    }


def _estimate_vars(rec: EpochRecord) -> dict:
    """Each receiver's estimates per candidate."""
    return {
        "aod_hat": (
            _RD,
            rec.meas["aod_rad"],
            {"units": "rad", "long_name": "AOD estimate (source eq. 7), NaN if nothing detected"},
        ),
        "toa_hat": (
            _RD,
            rec.meas["toa_s"],
            {"units": "s", "long_name": "TOA estimate (source eq. 9), NaN if nothing detected"},
        ),
        "peak": (
            _RD,
            rec.meas["peak"],
            {"units": "1", "long_name": "combined correlation peak (decimated-rate units)"},
        ),
        "best_score": (
            _RD,
            rec.meas["best_score"],
            {"units": "1", "long_name": "largest (eta - mu)/sigma over detected blocks"},
        ),
        "n_detected": (_RD, rec.meas["n_detected"], {"units": "1", "long_name": "SS blocks detected (source eq. 6)"}),
    }
