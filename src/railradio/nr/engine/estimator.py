"""The receivers of :class:`railradio.nr.engine.simulate.Estimator` on one shared set of
correlations (:class:`railradio.nr.receiver.shared.SharedCorrelation`): the same cell
search, the same receivers and the same epoch logic, each correlation computed once.
"""

from __future__ import annotations

import numpy as np

from railradio.nr.engine.simulate import Estimator, Scenario
from railradio.nr.receiver.correlator import BlockCorrelation, Correlator
from railradio.nr.receiver.shared import SharedCorrelation


class _Receiver:
    """A receiver's correlator as the estimator and the cell search call it, served from the
    shared correlations: the first call on a burst's window spectra and candidates computes
    every receiver of its group at once (the estimator's receivers: all of them; the cell
    search: itself), a later call of the group reads the result."""

    def __init__(self, cor: Correlator, shared: SharedCorrelation, index: int, group: list[int], cache: dict):
        self.cor, self.shared, self.index, self.group, self.cache = cor, shared, index, group, cache
        self.n_win = cor.n_win

    def window_spectra(self, z: np.ndarray, s_min: int) -> np.ndarray:
        """The correlator's window spectra (:meth:`Correlator.window_spectra`)."""
        return self.cor.window_spectra(z, s_min)

    def correlate(self, z, s_min, n_id1, n_id2, keep_corr: bool = False, zf=None) -> BlockCorrelation:
        """:meth:`Correlator.correlate` from the shared correlations."""
        if zf is None:
            zf = self.cor.window_spectra(z, s_min)
        key = (tuple(int(v) for v in n_id1), tuple(int(v) for v in n_id2))
        held = self.cache.get("zf")
        if held is not zf or key not in self.cache:
            if held is not zf:
                self.cache.clear()
                self.cache["zf"] = zf
            group = self.group if self.index in self.group else [self.index]
            res = self.shared.correlate(zf, n_id1, n_id2, which=group, keep_corr=keep_corr and group[0] == self.index)
            self.cache[key] = dict(zip(group, res, strict=True))
        got = self.cache[key]
        if self.index not in got:  # not part of that group's call
            got[self.index] = self.shared.correlate(zf, n_id1, n_id2, which=[self.index], keep_corr=keep_corr)[0]
        return got[self.index]


class SharedEstimator(Estimator):
    """:class:`railradio.nr.engine.simulate.Estimator` whose receivers and cell search read one
    :class:`SharedCorrelation` (burst + deployment + own state -> measurements; no truth).

    Parameters
    ----------
    scn : Scenario
        The scenario (as :class:`Estimator`).
    on_lag_grid : bool
        The bursts come on the correlation's lag grid F_s/D_c already
        (:class:`railradio.nr.engine.frontend.SpectralSynthesis`), not at the front end's
        F_s/D: no interpolation here.
    """

    def __init__(self, scn: Scenario, on_lag_grid: bool = False):
        super().__init__(scn)
        if on_lag_grid:
            self.up = 1
        cors = list(self.cors)
        cs_index = self.cs_shared
        if cs_index is None:
            cors.append(self.search.correlator)
            cs_index = len(cors) - 1
        self.shared = SharedCorrelation(cors)
        cache: dict = {}
        group = list(range(len(self.cors)))
        self.cors = [_Receiver(c, self.shared, j, group, cache) for j, c in enumerate(self.cors)]
        self.search.correlator = _Receiver(cors[cs_index], self.shared, cs_index, [cs_index], cache)
