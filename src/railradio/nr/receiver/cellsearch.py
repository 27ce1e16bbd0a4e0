"""The train's cell search: which RRHs it measures at each epoch, from its own bursts only.

A UE measures the neighbour cells the network names for its serving cell; it never knows
where it is. The receiver here does the same with the deployment (RRH positions and PCIs)
and its own measurements:

- **SS-RSRP** per cell (TS 38.215 §5.1.1: the power of the resource elements carrying the
  cell's SSS). Every RRH's SSS sits on the same 127 resource elements, so the power is made
  PCI-specific by despreading: the squared magnitude of the cell's SSS correlation at its
  detected timing, per SS block; the cell's value is its best detected block (the beam
  consolidation of TS 38.331 §5.5.3.3 with one beam). Units: dB on an arbitrary reference
  common to every cell (only the ranking and differences enter).
- **Neighbour list**: the ``n_neighbours`` RRHs of the deployment nearest the *anchor* cell
  (the anchor first), the cells the network would name around a serving cell.
- **Anchor**: set by a blind acquisition (every PCI of the deployment searched, the
  strongest SS-RSRP); between acquisitions it follows the strongest cell of its list only
  when that cell has been the strongest for ``confirm_epochs`` consecutive epochs (a
  detector with false alarms must not move the list).
- **Acquisition epochs** are fixed: every ``acquire_every`` epochs (and the next epoch
  after the anchor has gone undetected for ``lost_epochs`` epochs, the receiver's own loss
  test). An acquisition resets all state, so an epoch's list depends only on the bursts
  since the last fixed acquisition epoch: a shard starting elsewhere replays those epochs
  first (:func:`warmup_start`), and results do not depend on the shard count.

Settings [ours]: SSS template and the CA-CFAR detector (the SSS is PCI-specific; the
combined PSS+SSS peak is not); 10 s between blind acquisitions (at 360 km/h a wrong list
lives at most 1 km, two RRH spacings); 3 epochs to confirm (39 m at 360 km/h, 8 % of the
spacing); 10 epochs (1 s) without the anchor before a new search.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from railradio.nr.channel.geometry import Deployment
from railradio.nr.receiver.config import ReceiverConfig
from railradio.nr.receiver.correlator import BlockCorrelation, Correlator


@dataclass(frozen=True)
class CellSearchConfig:
    """Cell-search settings [ours]; see the module docstring for the rule behind each.

    Raises
    ------
    ValueError
        When ``n_neighbours``, ``acquire_every``, ``confirm_epochs`` or ``lost_epochs`` is not an
        integer ≥ 1, or ``pfa`` is outside (0, 1).
    """

    template: str = "sss"
    detector: str = "cacfar"
    pfa: float = 1e-3
    n_neighbours: int = 6
    acquire_every: int = 100
    confirm_epochs: int = 3
    lost_epochs: int = 10

    def __post_init__(self) -> None:
        for name in ("n_neighbours", "acquire_every", "confirm_epochs", "lost_epochs"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
        if not 0 < self.pfa < 1:
            raise ValueError(f"pfa must be in (0, 1), got {self.pfa!r}")

    def receiver_config(self, burst: ReceiverConfig) -> ReceiverConfig:
        """The correlation settings of the search on bursts of ``burst``'s decimation,
        SS-block pattern and window.

        Parameters
        ----------
        burst : ReceiverConfig
            The front end's receiver configuration (decimation, SS-block pattern and count, lag
            window, detection and pre-screen thresholds are taken from it).

        Returns
        -------
        ReceiverConfig
            A new configuration with the burst's decimation, SS-block pattern and count,
            ``search_lags``, ``detect_k_sigma`` and ``prescreen_k_sigma``, and this search's
            ``template``; its other fields at their defaults.
        """
        return ReceiverConfig(
            decimation=burst.decimation,
            ssb_pattern=burst.ssb_pattern,
            n_blocks=burst.n_blocks,
            search_lags=burst.search_lags,
            detect_k_sigma=burst.detect_k_sigma,
            prescreen_k_sigma=burst.prescreen_k_sigma,
            template=self.template,
        )


def correlation_key(cfg: ReceiverConfig, detector: str, pfa: float) -> tuple:
    """What the per-block statistics (η, μ, σ, detection) of a correlator depend on: two
    correlators with the same key give the same :class:`BlockCorrelation` detections.

    Parameters
    ----------
    cfg : ReceiverConfig
        The correlator's receiver configuration.
    detector : str
        Detection rule (:data:`railradio.nr.receiver.correlator.DETECTORS`).
    pfa : float
        False-alarm probability per block of the CFAR tests.

    Returns
    -------
    tuple
        (decimation, SS-block pattern, n_blocks, search_lags, detect_k_sigma,
        prescreen_k_sigma, template, detector, pfa).
    """
    return (
        cfg.decimation,
        cfg.ssb_pattern,
        cfg.n_blocks,
        cfg.search_lags,
        cfg.detect_k_sigma,
        cfg.prescreen_k_sigma,
        cfg.template,
        detector,
        float(pfa),
    )


def ss_rsrp_db(res: BlockCorrelation) -> NDArray[np.float64]:
    """SS-RSRP per candidate [dB, arbitrary common reference]: 10 log10 of the largest
    squared SSS correlation η² over the candidate's detected blocks; NaN if none.

    Parameters
    ----------
    res : BlockCorrelation
        The candidates' correlation (``eta``, ``detected`` [n_cand, n_blocks]).

    Returns
    -------
    numpy.ndarray
        SS-RSRP [dB, arbitrary common reference], [n_cand]; NaN where no block is detected.
    """
    p = np.where(res.detected, np.asarray(res.eta, float) ** 2, -np.inf).max(axis=1)
    with np.errstate(divide="ignore"):
        out = 10 * np.log10(np.where(np.isfinite(p), p, np.nan))
    return out


def neighbour_list(dep: Deployment, anchor: int, n: int) -> NDArray[np.int64]:
    """The ``n`` RRHs nearest RRH ``anchor`` along the track, the anchor first (ties: the
    lower index first).

    Parameters
    ----------
    dep : Deployment
        The RRH deployment.
    anchor : int
        Index of the anchor RRH, in ``0..dep.n_rrh - 1``.
    n : int
        List length (at most ``dep.n_rrh`` are returned).

    Returns
    -------
    numpy.ndarray of int64
        RRH indices, [min(n, n_rrh)], the anchor first.

    Raises
    ------
    ValueError
        When ``anchor`` is not an RRH index of ``dep``.
    """
    if not 0 <= anchor < dep.n_rrh:
        raise ValueError(f"anchor must be in 0..{dep.n_rrh - 1}, got {anchor!r}")
    return dep.nearest(float(dep.x_m[anchor]), min(n, dep.n_rrh)).astype(np.int64)


def warmup_start(epoch: int, acquire_every: int) -> int:
    """The fixed acquisition epoch at or before ``epoch``: where a run that must produce
    ``epoch`` starts (the epochs in between are replayed, not reported).

    Parameters
    ----------
    epoch : int
        The epoch to produce (≥ 0).
    acquire_every : int
        Period of the fixed acquisition epochs, epochs (≥ 1).

    Returns
    -------
    int
        The largest multiple of ``acquire_every`` not above ``epoch``.
    """
    return int(epoch) - int(epoch) % int(acquire_every)


class CellSearch:
    """The receiver's cell-search state over consecutive epochs (no truth: it sees the
    deployment and the bursts' correlations only).

    Per epoch: :meth:`candidates` (the list to measure, after a blind acquisition if one is
    due, which needs the burst), then :meth:`update` with the list's correlation.
    """

    def __init__(self, cfg: CellSearchConfig, deployment: Deployment, correlator: Correlator):
        """Start in the searching state (no anchor: the first epoch runs a blind acquisition).

        Parameters
        ----------
        cfg : CellSearchConfig
            The cell-search settings.
        deployment : Deployment
            RRH positions and PCIs (the receiver's only knowledge of the network).
        correlator : Correlator
            The correlator measuring SS-RSRP (:meth:`CellSearchConfig.receiver_config`'s settings).
        """
        self.cfg, self.dep, self.correlator = cfg, deployment, correlator
        self.n_id1, self.n_id2 = deployment.n_id()
        self.reset()

    def reset(self) -> None:
        """Forget all state (anchor, challenger, counts): the next epoch runs a blind acquisition."""
        self.anchor = -1
        self.searching = True
        self.challenger, self.count, self.misses = -1, 0, 0

    def acquire(self, z, s_min: int, zf=None) -> None:
        """Blind acquisition: every PCI of the deployment, the strongest SS-RSRP becomes the
        anchor. When nothing is detected the largest correlation (η² over all blocks) is
        taken, and the search repeats at the next epoch.

        Parameters
        ----------
        z : numpy.ndarray of complex64
            The burst's samples at the correlator's rate, [n_samples].
        s_min : int
            Symbol index of the burst's first sample.
        zf : numpy.ndarray of complex64 or None
            The burst's :meth:`railradio.nr.receiver.correlator.Correlator.window_spectra`, [n_blocks, n_win]
            (``None``: computed here).
        """
        res = self.correlator.correlate(z, s_min, self.n_id1, self.n_id2, zf=zf)
        rsrp = ss_rsrp_db(res)
        self.reset()
        if np.isfinite(rsrp).any():
            self.anchor = int(np.nanargmax(rsrp))
            self.searching = False
        else:
            self.anchor = int(np.argmax(np.asarray(res.eta, float).max(axis=1)))

    def candidates(self, epoch: int, z, s_min: int, zf=None) -> tuple[NDArray[np.int64], bool]:
        """The neighbour list measured at ``epoch`` and whether a blind acquisition ran.

        An acquisition runs at the fixed acquisition epochs, while searching and when there is
        no anchor.

        Parameters
        ----------
        epoch : int
            Epoch index.
        z : numpy.ndarray of complex64
            The burst's samples at the correlator's rate, [n_samples] (read only when an
            acquisition runs, as are ``s_min`` and ``zf``).
        s_min : int
            Symbol index of the burst's first sample.
        zf : numpy.ndarray of complex64 or None
            The burst's window spectra, [n_blocks, n_win], as in :meth:`acquire`.

        Returns
        -------
        tuple
            (RRH indices to measure, int64 [min(n_neighbours, n_rrh)], anchor first;
            whether a blind acquisition ran, bool).
        """
        acquired = int(epoch) % self.cfg.acquire_every == 0 or self.searching or self.anchor < 0
        if acquired:
            self.acquire(z, s_min, zf)
        return neighbour_list(self.dep, self.anchor, self.cfg.n_neighbours), acquired

    def update(self, cand: NDArray[np.int64], rsrp_db: NDArray[np.float64]) -> None:
        """Follow the strongest cell of the list once confirmed; start a new search after
        ``lost_epochs`` epochs without the anchor.

        Parameters
        ----------
        cand : numpy.ndarray of int64
            The epoch's neighbour list (:meth:`candidates`), [n_cand].
        rsrp_db : numpy.ndarray
            Its SS-RSRP (:func:`ss_rsrp_db`) [dB, arbitrary common reference], [n_cand]; NaN: not detected.
        """
        cand = np.asarray(cand)
        at = np.flatnonzero(cand == self.anchor)
        if at.size and np.isfinite(rsrp_db[at[0]]):
            self.misses = 0
        else:
            self.misses += 1
            if self.misses >= self.cfg.lost_epochs:
                self.searching = True
        if not np.isfinite(rsrp_db).any():
            self.challenger, self.count = -1, 0
            return
        best = int(cand[int(np.nanargmax(rsrp_db))])
        if best == self.anchor:
            self.challenger, self.count = -1, 0
            return
        self.count = self.count + 1 if best == self.challenger else 1
        self.challenger = best
        if self.count >= self.cfg.confirm_epochs:
            self.anchor, self.challenger, self.count, self.misses = best, -1, 0, 0
