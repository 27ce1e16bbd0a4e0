"""Large-scale link budget of every RRH in range at one epoch (source eq. 1; docs/model/nr.md §1, §3).

P_R = P_T - PL(d3D) + S + G_T(θ_T) + G_R(θ_R): the transmit power is spread evenly over the
600 active subcarriers (equal EPRE); beam gains from :mod:`railradio.nr.channel.antenna`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.nr.channel.antenna import RrhArray, TrainArray
from railradio.nr.channel.geometry import Deployment
from railradio.nr.channel.tdl import pathloss_umi_los_db, shadowing_field_db
from railradio.nr.waveform.numerology import N_ACTIVE
from railradio.rng import make_rng


@dataclass
class Links:
    """Everything about the RRHs in range at one epoch (arrays over RRHs).

    Attributes
    ----------
    n_id1, n_id2 : [R] int
    tau_s : [R] bulk 3-D delay [s]
    amp : [R] amplitude [√W] per unit-EPRE subcarrier: √(P_sc · G_R / PL · 10^{S/10})
    beam_amp : [R, n_beams] Tx beam amplitude gains toward the train [linear, √]
    data_amp : [R] Tx amplitude gain of the data beam (best beam toward the train)
    f_los_hz : [R] LOS Doppler f_D cos α [Hz]
    phase0 : [R] LOS carrier phase at t = 0 [rad]
    doppler_hz : maximum Doppler v/λ [Hz]
    noise_psd_w_hz : N0 of one receive chain [W/Hz]
    n_chains : receive chains summed (noise adds)
    """

    n_id1: NDArray[np.int64]
    n_id2: NDArray[np.int64]
    tau_s: NDArray[np.float64]
    amp: NDArray[np.float64]
    beam_amp: NDArray[np.float64]
    data_amp: NDArray[np.float64]
    f_los_hz: NDArray[np.float64]
    phase0: NDArray[np.float64]
    doppler_hz: float
    noise_psd_w_hz: float
    n_chains: int = 2
    extra: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of links R (int): ``tau_s.size``."""
        return int(self.tau_s.size)


BOLTZMANN_DBM_HZ = -174.0


@dataclass(frozen=True)
class RadioParams:
    """Radio parameters [source unless noted].

    carrier_hz 30 GHz; tx_power_dbm 33 (whole carrier); noise_figure_db 5;
    shadow_sigma_db 4 and shadow_corr_m 10 [3GPP UMi-LOS]; range_m: RRHs within this 2-D
    distance are synthesized (5 km: the UMi model's validity) [ours].
    """

    carrier_hz: float = 30e9
    tx_power_dbm: float = 33.0
    noise_figure_db: float = 5.0
    shadow_sigma_db: float = 4.0
    shadow_corr_m: float = 10.0
    range_m: float = 5000.0

    @property
    def wavelength_m(self) -> float:
        """Carrier wavelength λ = c / f_c.

        Returns
        -------
        float
            Wavelength [m].
        """
        return SPEED_OF_LIGHT_M_S / self.carrier_hz

    @property
    def noise_psd_w_hz(self) -> float:
        """Noise power spectral density N0 of one receive chain: -174 dBm/Hz + noise figure.

        Returns
        -------
        float
            N0 [W/Hz].
        """
        return 10 ** ((BOLTZMANN_DBM_HZ + self.noise_figure_db - 30) / 10)

    @property
    def epre_w(self) -> float:
        """Energy per resource element: the transmit power spread evenly over the N_ACTIVE subcarriers.

        Returns
        -------
        float
            Power per subcarrier [W].
        """
        return 10 ** ((self.tx_power_dbm - 30) / 10) / N_ACTIVE


class ShadowingMap:
    """Spatially correlated shadowing of each RRH along the track, on a 1 m grid.

    The field of RRH k spans [x_k - range, x_k + range] and is drawn from its own generator
    (seed, realization, k), so it is the same in every shard of the track.

    Parameters
    ----------
    seed : int
        The config seed.
    key : tuple of int
        Spawn key of the shadowing (the realization's key + ``KEY_SHADOWING``).
    dep : Deployment
        RRH positions (``x_m``, m).
    radio : RadioParams
        Uses ``range_m`` (m), ``shadow_sigma_db`` (dB) and ``shadow_corr_m`` (decorrelation distance, m).
    """

    def __init__(self, seed: int, key: tuple[int, ...], dep: Deployment, radio: RadioParams):
        self.seed, self.key, self.dep, self.radio = seed, key, dep, radio
        self._fields: dict[int, NDArray[np.float64]] = {}

    def field(self, rrh: int) -> NDArray[np.float64]:
        """The shadowing field of one RRH (drawn on first use, then cached).

        Parameters
        ----------
        rrh : int
            RRH index k.

        Returns
        -------
        numpy.ndarray
            Shadowing [dB] on a 1 m grid, point i at x_k - range_m + i [m]:
            [int(2·range_m) + 2].
        """
        if rrh not in self._fields:
            n = int(2 * self.radio.range_m) + 2
            rng = make_rng(self.seed, self.key + (int(rrh),))
            self._fields[rrh] = shadowing_field_db(rng, n, self.radio.shadow_sigma_db, self.radio.shadow_corr_m)
        return self._fields[rrh]

    def at(self, x_m: float, rrh: NDArray[np.int64]) -> NDArray[np.float64]:
        """Shadowing of the RRHs ``rrh`` toward a receiver at ``x_m`` (nearest grid point).

        Parameters
        ----------
        x_m : float
            Receiver position along the track [m]; positions beyond a field's ends take
            its end values.
        rrh : numpy.ndarray of int64
            RRH indices: [R].

        Returns
        -------
        numpy.ndarray
            Shadowing [dB]: [R].
        """
        out = np.empty(len(rrh))
        for i, k in enumerate(rrh):
            pos = int(round(x_m - self.dep.x_m[k] + self.radio.range_m))
            f = self.field(int(k))
            out[i] = f[min(max(pos, 0), f.size - 1)]
        return out


@dataclass
class LinkBudget:
    """Per-epoch large-scale quantities of the RRHs in range (arrays over RRHs; with
    separate train panels, the panel that receives each RRH more strongly — ``panel``).

    ``links`` holds the synthesis inputs: one link per RRH (co-located panels) or one per
    RRH and panel, RRH-major (``link_rrh``, ``link_d2d_m``, ``link_panel_x_m``: the RRH
    index, the 2-D distance and the receiving panel's along-track offset of each link)."""

    rrh: NDArray[np.int64]
    d3d_m: NDArray[np.float64]
    pathloss_db: NDArray[np.float64]
    shadowing_db: NDArray[np.float64]
    aod_rad: NDArray[np.float64]
    aoa_rad: NDArray[np.float64]
    beam_gain_db: NDArray[np.float64]  # [R, n_beams]
    rx_gain_db: NDArray[np.float64]
    links: Links
    panel: NDArray[np.int64] | None = None
    link_rrh: NDArray[np.int64] | None = None
    link_d2d_m: NDArray[np.float64] | None = None
    link_panel_x_m: NDArray[np.float64] | None = None

    @cached_property
    def rx_power_dbm(self) -> NDArray[np.float64]:
        """Received power over the carrier with the best beam [dBm].

        Returns
        -------
        numpy.ndarray
            P_T - PL + S + max beam gain + receive gain per RRH in range [dBm]: [R].
        """
        return (
            self.links.extra["tx_power_dbm"]
            - self.pathloss_db
            + self.shadowing_db
            + self.beam_gain_db.max(axis=1)
            + self.rx_gain_db
        )


def link_budget(
    x_m: float,
    speed_m_s: float,
    dep: Deployment,
    radio: RadioParams,
    rrh_array: RrhArray,
    train: TrainArray,
    shadow: ShadowingMap,
    shadowing: bool = True,
) -> LinkBudget:
    """Large-scale parameters and the synthesis inputs of every RRH within ``radio.range_m``
    of the train's reference point ``x_m``.

    Parameters
    ----------
    x_m : float
        Train reference position along the track, m.
    speed_m_s : float
        Train speed, m/s (sets the Doppler).
    dep : Deployment
        The RRH deployment.
    radio : RadioParams
        Link parameters (powers dBm, noise figure dB, carrier Hz, ``range_m`` m, shadowing).
    rrh_array : RrhArray
        The RRHs' antenna array and SS beams.
    train : TrainArray
        The train's antenna array and panels.
    shadow : ShadowingMap
        The realization's shadowing fields.
    shadowing : bool
        Apply the shadowing (False: 0 dB).

    Returns
    -------
    LinkBudget
        The RRHs in range (``rrh``), their received powers ``rx_power_dbm`` [dBm] and geometry,
        and the synthesis inputs ``links`` (:class:`railradio.nr.channel.link.Links`).
    """
    d2d_all = np.hypot(dep.x_m - x_m, dep.offset_m)
    rrh = np.flatnonzero(d2d_all <= radio.range_m)
    paths = _Paths(dep, radio, rrh_array, shadow, shadowing, rrh)
    if train.co_located:
        return _co_located_budget(paths, x_m, speed_m_s, train)
    return _panel_budget(paths, x_m, speed_m_s, train)


@dataclass(frozen=True)
class _Paths:
    """The paths of the RRHs ``rrh`` in range to a receiver anywhere on the track."""

    dep: Deployment
    radio: RadioParams
    rrh_array: RrhArray
    shadow: ShadowingMap
    shadowing: bool
    rrh: NDArray[np.int64]

    def path(self, xp: float, gain_db) -> dict:
        """Geometry and large-scale terms of every RRH's path to a receiver at ``xp``;
        ``gain_db(aoa)``: its receive gain [dBi].

        Parameters
        ----------
        xp : float
            Receiver (panel) position along the track [m].
        gain_db : callable
            Maps AOA [rad], [R], to the receive gain [dBi], [R].

        Returns
        -------
        dict
            ``xp`` [m]; over the R RRHs ``rrh``: ``d3d``, ``d2d`` [m], ``aod``, ``aoa`` [rad],
            ``gt`` [dBi] ([R, n_beams]), ``gr`` [dBi], ``pl`` [dB] and ``sh`` [dB] (0 without
            shadowing), each [R] unless noted.
        """
        dep, radio, rrh = self.dep, self.radio, self.rrh
        d3d = dep.distance_3d_m(xp, rrh)
        d2d = dep.distance_2d_m(xp, rrh)
        aod = dep.aod_rad(np.full(rrh.size, xp), rrh)
        aoa = dep.aoa_rad(np.full(rrh.size, xp), rrh)
        return dict(
            xp=xp,
            d3d=d3d,
            d2d=d2d,
            aod=aod,
            aoa=aoa,
            gt=self.rrh_array.beam_gains_db(aod),
            gr=gain_db(aoa),
            pl=pathloss_umi_los_db(d3d, d2d, radio.carrier_hz, dep.h_bs_m, dep.h_ut_m),
            sh=self.shadow.at(xp, rrh) if self.shadowing else np.zeros(rrh.size),
        )


def _co_located_budget(paths: _Paths, x_m: float, speed_m_s: float, train: TrainArray) -> LinkBudget:
    """The link budget of co-located train panels: one link per RRH."""
    dep, radio, rrh = paths.dep, paths.radio, paths.rrh
    n1, n2 = dep.n_id()
    lam = radio.wavelength_m
    c = paths.path(x_m, train.gain_db)
    d3d, d2d, pl, sh, aod, aoa, gt, gr = (c[k] for k in ("d3d", "d2d", "pl", "sh", "aod", "aoa", "gt", "gr"))
    amp = np.sqrt(radio.epre_w * 10 ** ((-pl + sh + gr) / 10))
    links = Links(
        n_id1=n1[rrh],
        n_id2=n2[rrh],
        tau_s=d3d / SPEED_OF_LIGHT_M_S,
        amp=amp,
        beam_amp=10 ** (gt / 20),
        data_amp=10 ** (gt.max(axis=1) / 20),
        f_los_hz=speed_m_s / lam * (dep.x_m[rrh] - x_m) / d3d,
        phase0=(-2 * np.pi * d3d / lam) % (2 * np.pi),
        doppler_hz=abs(speed_m_s) / lam,
        noise_psd_w_hz=radio.noise_psd_w_hz,
        n_chains=train.n_chains,
        extra={"tx_power_dbm": radio.tx_power_dbm},
    )
    return LinkBudget(
        rrh, d3d, pl, sh, aod, aoa, gt, gr, links, link_rrh=rrh, link_d2d_m=d2d, link_panel_x_m=np.zeros(rrh.size)
    )


def _panel_budget(paths: _Paths, x_m: float, speed_m_s: float, train: TrainArray) -> LinkBudget:
    """The link budget of separate train panels: one link per RRH and panel, RRH-major."""
    dep, radio, rrh = paths.dep, paths.radio, paths.rrh
    n1, n2 = dep.n_id()
    lam = radio.wavelength_m
    # separate panels: each RRH reaches the head panel at x + panel_x[0] and the tail panel
    # at x + panel_x[1] over its own path (delay, path loss, shadowing, angles, fading)
    per = []
    for panel, dx_panel in enumerate(train.panel_x_m):
        p = paths.path(x_m + float(dx_panel), lambda aoa, panel=panel: train.panel_gain_db(aoa, panel))
        per.append(p | {"power": -p["pl"] + p["sh"] + p["gr"] + p["gt"].max(axis=1)})
    panel = np.argmax(np.stack([p["power"] for p in per]), axis=0)  # [R] the stronger panel
    pick = {k: np.choose(panel, [p[k] for p in per]) for k in ("d3d", "pl", "sh", "aod", "aoa", "gr")}
    gt_serv = np.where(panel[:, None] == 0, per[0]["gt"], per[1]["gt"])
    # one data beam per RRH: its best beam toward the stronger panel, seen by both panels
    b_data = gt_serv.argmax(axis=1)
    cols = {k: np.stack([p[k] for p in per], axis=1).ravel() for k in ("d3d", "d2d", "pl", "sh", "gr")}
    gt_l = np.stack([p["gt"] for p in per], axis=1).reshape(-1, paths.rrh_array.n_beams)  # [2R, beams]
    x_rrh_l = np.repeat(dep.x_m[rrh], 2)
    xp_l = np.tile([per[0]["xp"], per[1]["xp"]], rrh.size)
    links = Links(
        n_id1=np.repeat(n1[rrh], 2),
        n_id2=np.repeat(n2[rrh], 2),
        tau_s=cols["d3d"] / SPEED_OF_LIGHT_M_S,
        amp=np.sqrt(radio.epre_w * 10 ** ((-cols["pl"] + cols["sh"] + cols["gr"]) / 10)),
        beam_amp=10 ** (gt_l / 20),
        data_amp=10 ** (gt_l[np.arange(gt_l.shape[0]), np.repeat(b_data, 2)] / 20),
        f_los_hz=speed_m_s / lam * (x_rrh_l - xp_l) / cols["d3d"],
        phase0=(-2 * np.pi * cols["d3d"] / lam) % (2 * np.pi),
        doppler_hz=abs(speed_m_s) / lam,
        noise_psd_w_hz=radio.noise_psd_w_hz,
        n_chains=train.n_chains,
        extra={"tx_power_dbm": radio.tx_power_dbm},
    )
    return LinkBudget(
        rrh,
        pick["d3d"],
        pick["pl"],
        pick["sh"],
        pick["aod"],
        pick["aoa"],
        gt_serv,
        pick["gr"],
        links,
        panel=panel,
        link_rrh=np.repeat(rrh, 2),
        link_d2d_m=cols["d2d"],
        link_panel_x_m=np.tile(np.asarray(train.panel_x_m, float), rrh.size),
    )
