"""The study's receivers on one burst, as the fidelity target runs them: each receiver's
decisions (block detections, TOA, AOD, the selected cells) at a chosen correlation rate."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from railradio.nr.engine.simulate import Scenario
from railradio.nr.receiver.cellsearch import correlation_key, ss_rsrp_db
from railradio.nr.receiver.correlator import Correlator


@dataclass
class ReceiverDecisions:
    """One receiver's decisions on one burst (arrays over the candidates)."""

    detected: NDArray[np.bool_]  # [cand, block]
    toa_samples: NDArray[np.float64]  # [cand] full-rate samples, NaN: nothing detected
    aod_rad: NDArray[np.float64]  # [cand]
    strength: NDArray[np.float64]  # [cand] what the receiver selects its cells by
    selected: NDArray[np.bool_]  # [cand]


class Receivers:
    """The study's receivers (the source's and the extra receivers, ``Scenario.extra_receivers``) and the
    cell search's SS-RSRP correlator at one rate: the front end's (``nr.receiver.decimation``),
    as in production, or a finer one on the front end's samples band-limited-interpolated
    (1: every full-rate lag; the template zero-stuffed, the CA-CFAR window and guard the same
    duration)."""

    def __init__(self, scn: Scenario, selection: dict[str, str], decimation: int, n_use: int = 3):
        """One correlator per receiver at F_s/``decimation`` (and the cell search's, unless a
        receiver's settings equal it).

        Parameters
        ----------
        scn : Scenario
            The scenario (its ``receiver``, ``detector``, ``extra_receivers``, ``pfa``, ``cell_search``).
        selection : dict of str to str
            Receiver name -> the strength it selects its cells by (``ss_rsrp``, ``best_score`` or ``peak``).
        decimation : int
            D_c: the correlation rate F_s/D_c (a divisor of the front end's decimation).
        n_use : int
            Cells selected per receiver.

        Raises
        ------
        ValueError
            From :class:`railradio.nr.receiver.correlator.Correlator` when ``decimation`` does not divide
            ``scn.receiver.decimation``.
        """
        base = scn.receiver.decimation
        self.decimation = decimation
        rx = [("source", scn.receiver, scn.detector)] + list(scn.extra_receivers)
        self.names = [name for name, _, _ in rx]
        self.selection = selection
        self.n_use = n_use

        def cor(rc, det, pfa):
            return Correlator(dataclasses.replace(rc, decimation=decimation), det, pfa, template_decimation=base)

        self.cors = [cor(rc, det, scn.pfa) for _, rc, det in rx]
        cs = scn.cell_search
        cs_rc = cs.receiver_config(scn.receiver)
        key = correlation_key(cs_rc, cs.detector, cs.pfa)
        self.cs_shared = next(
            (j for j, (_, rc, det) in enumerate(rx) if correlation_key(rc, det, scn.pfa) == key), None
        )
        self.cs_cor = None if self.cs_shared is not None else cor(cs_rc, cs.detector, cs.pfa)

    def __call__(self, z: NDArray[np.complex64], s_min: int, n1: NDArray, n2: NDArray) -> dict[str, ReceiverDecisions]:
        """Every receiver's decisions on one burst.

        Parameters
        ----------
        z : numpy.ndarray of complex64
            The burst's samples at the correlation rate F_s/D_c, [n_samples].
        s_min : int
            Symbol index of the burst's first sample.
        n1, n2 : numpy.ndarray of int
            The candidates' N_ID1 and N_ID2, [n_cand] each.

        Returns
        -------
        dict of str to ReceiverDecisions
            Receiver name -> its decisions (TOA [full-rate samples], AOD [rad]; strength: SS-RSRP [dB,
            arbitrary reference], best score or peak; the ``n_use`` strongest with TOA and AOD selected).
        """
        spectra = {}

        def zf(c):
            if c.n_win not in spectra:
                spectra[c.n_win] = c.window_spectra(z, s_min)
            return spectra[c.n_win]

        res = [c.correlate(z, s_min, n1, n2, zf=zf(c)) for c in self.cors]
        cs_res = (
            res[self.cs_shared]
            if self.cs_shared is not None
            else self.cs_cor.correlate(z, s_min, n1, n2, zf=zf(self.cs_cor))
        )
        rsrp = ss_rsrp_db(cs_res)
        out = {}
        for name, r in zip(self.names, res, strict=True):
            score = np.where(r.detected, (r.eta - r.mu) / np.maximum(r.sigma, 1e-30), -np.inf)
            best = np.where(r.detected.any(axis=1), score.max(axis=1), np.nan)
            strength = {"ss_rsrp": rsrp, "best_score": best, "peak": r.peak_comb}[self.selection[name]]
            ok = np.isfinite(r.aod_rad) & np.isfinite(r.toa_samples)
            s = np.where(ok, np.nan_to_num(strength, nan=-np.inf), -np.inf)
            order = np.argsort(-s)[: self.n_use]  # railradio.nr.tracking.calibration.selected, one epoch
            sel = np.zeros(n1.size, dtype=bool)
            sel[order[ok[order]]] = True
            out[name] = ReceiverDecisions(
                r.detected.copy(), r.toa_samples.copy(), r.aod_rad.copy(), np.asarray(strength, float), sel
            )
        return out
