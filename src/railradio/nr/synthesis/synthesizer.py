"""Received SS bursts (source eq. 2–3): the transmitter and channel synthesizer.

Synthesis (per epoch, :class:`Synthesizer`): every RRH in range sends its burst grid (PSS,
SSS, PBCH, full-buffer data; SS-block symbols on that block's beam, other symbols on their
data beam) through its own channel: bulk 3-D delay τ0 (TS 38.211's time-continuous symbols
sampled exactly: a per-symbol phase ramp e^{-j2π f_k τ0} and each symbol's extent placed at
⌈τ0 F_s⌉), TDL taps (per-symbol Rayleigh gains, fixed-delay basis e^{-j2π f_k τ_l}) and the
LOS tap's Doppler as a continuous phase within every symbol (inter-carrier interference);
plus AWGN. Its shortcuts, each measured against the exact computation
(:func:`railradio.nr.synthesis.reference.reference_received`) on paper-scale epochs by the fidelity
target (:mod:`railradio.nr.study.fidelity`):

* a band: only the N_FFT/D_s central subcarriers are synthesized (at F_s/D_s), then the
  receiver's front end filters to its own band;
* the Rayleigh taps are held per symbol and rotate within a symbol with the LOS Doppler;
  each delayed tap's copy of a symbol is wrapped within the symbol's extent (its spill into
  the next symbol is omitted) unless ``exact_spill``, as the study configures;
* the geometry (bulk delay, LOS Doppler, beam gains) is held over the 2 ms burst (the train
  moves ≤ 0.26 m, 0.2 full-rate samples); ``motion`` follows it symbol by symbol.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

import railradio.nr.synthesis.kernels as kernels
from railradio.nr.channel.link import Links
from railradio.nr.channel.tdl import TdlProfile, sos_params
from railradio.nr.receiver.config import ReceiverConfig, fft_rows
from railradio.nr.synthesis.beams import at_train_mask, symbol_gains
from railradio.nr.synthesis.layout import BurstLayout
from railradio.nr.synthesis.spill import Spill
from railradio.nr.waveform.numerology import SUBCARRIER_SPACING_HZ
from railradio.nr.waveform.ssb import band_bins

DATA_BEAMS = ("serving", "train", "random", "none")


class _LinkGrid(NamedTuple):
    """One link's resource grid as :func:`kernels.fill_grid` takes it, for the symbols
    synthesized: the data pool rows, the SS-block overlay (:meth:`Synthesizer.overlay`), the
    delay's phase ramp [n], the per-symbol amplitude and the long-CP ramps."""

    pool_idx: NDArray[np.int64]
    ov: tuple[NDArray, ...]
    ramp: NDArray[np.complex64]
    g_row: NDArray[np.float32]
    long_of: NDArray[np.int64]
    long_ramp: NDArray[np.complex64]


class Synthesizer(BurstLayout):
    """Builds received bursts for one receiver configuration (caches per-cell grids).

    Traffic [ours, by the deployment rule of ``config/README.md``]: the full-buffer data of
    the resource elements outside the SS blocks (source) go, by ``data_beam``,

    - ``"serving"``: from the serving cell on its best beam toward the train (the train is
      its user); every other RRH, in each slot (14 symbols, the PDSCH scheduling unit of
      TS 38.214 §5.1.2) with probability ``load``, toward a uniformly drawn SS-beam
      direction (its own users along the track), and nothing in its other slots;
    - ``"train"``: every RRH toward the train (a worst case);
    - ``"random"``: every RRH as a non-serving one above;
    - ``"none"``: PSS and SSS only — the data pool is zeroed, and the PBCH, which draws its
      QPSK symbols from the same pool, goes with it.

    The random beams and loads are drawn for every RRH whatever the policy, so changing the
    policy or the serving cell changes no other draw.

    Parameters
    ----------
    cfg : ReceiverConfig
        The receiver configuration; its decimation D sets the synthesis rate F_s/D.
    profile : TdlProfile
        TDL power-delay profile (delays s, powers).
    pool : numpy.ndarray of complex64
        [n_pool, N_FFT] QPSK data symbols (:func:`railradio.nr.waveform.ssb.qpsk_pool`).
    n_sinusoids : int
        Sinusoids per tap of the sum-of-sinusoids fading.
    full_channel_range_m : float
        RRHs farther than this (2-D), m, are synthesized as one non-fading tap (inf: none).
    data_beam : str
        ``"serving"``, ``"train"``, ``"random"`` or ``"none"``.
    load : float
        Share of slots in which a non-serving RRH sends data, in [0, 1].
    exact_spill : bool
        Delayed taps spill into the next symbol as in the exact reference (False: wrapped).

    Raises
    ------
    ValueError
        When ``data_beam`` is unknown or ``load`` is outside [0, 1].
    """

    def __init__(
        self,
        cfg: ReceiverConfig,
        profile: TdlProfile,
        pool: NDArray[np.complex64],
        n_sinusoids: int = 16,
        full_channel_range_m: float = np.inf,
        data_beam: str = "serving",
        load: float = 1.0,
        exact_spill: bool = False,
    ):
        if data_beam not in DATA_BEAMS:
            raise ValueError(f"data_beam must be one of {DATA_BEAMS}, got {data_beam!r}")
        if not 0.0 <= load <= 1.0:
            raise ValueError(f"load must be in [0, 1], got {load!r}")
        self.data_beam, self.load = data_beam, float(load)
        super().__init__(cfg)
        self.profile = profile
        self.n_sinusoids = n_sinusoids
        self.full_channel_range_m = full_channel_range_m
        num = cfg.num
        band = pool[:, band_bins(num)]
        if data_beam == "none":
            band = np.zeros_like(band)
        # the last row is empty: the data of an idle slot
        self.pool_band = np.ascontiguousarray(np.vstack([band, np.zeros((1, band.shape[1]), band.dtype)]))
        self.idle_row = band.shape[0]
        n = num.n_fft
        self.k = np.fft.fftfreq(n, 1.0 / n)
        self.f_k = self.k * SUBCARRIER_SPACING_HZ
        self.basis = np.exp(-2j * np.pi * np.outer(profile.delays_s, self.f_k)).astype(np.complex64)
        self.exact_spill = exact_spill
        self.spill = Spill(profile, num)
        self.kept_gains: dict[int, NDArray[np.complex64]] = {}  # the last burst's tap gains by link (band edges)

    def draws(self, links: Links, rng: np.random.Generator) -> list[dict]:
        """The random draws of one burst per RRH: data pool indices, fading (α, φ), and per
        slot the beam and whether the slot carries data (used by non-serving RRHs).

        Parameters
        ----------
        links : Links
            The R links in range.
        rng : numpy.random.Generator
            The epoch's generator.

        Returns
        -------
        list of dict
            Per link: ``pool_idx`` [S], ``alpha``, ``phi`` [L, n_sinusoids] [rad], and per symbol (held
            over its slot) ``data_beam`` (SS-beam index) and ``busy`` (bool), [S].
        """
        sp = self.span(float(np.max(links.tau_s)) if links.n else 0.0)
        slot = sp["slot"]
        n_slots = int(slot.max()) + 1
        out = []
        for _ in range(links.n):
            idx = rng.integers(0, self.idle_row, size=sp["symbols"].size)
            alpha, phi = sos_params(rng, self.profile.powers.size, self.n_sinusoids)
            out.append({"pool_idx": idx, "alpha": alpha, "phi": phi})
        for d in out:  # after the data and fading draws, which therefore do not depend on it
            d["data_beam"] = rng.integers(0, self.cfg.n_blocks, size=n_slots)[slot]
            d["busy"] = (rng.random(n_slots) < self.load)[slot]
        return out

    def __call__(
        self,
        links: Links,
        rng: np.random.Generator,
        t0_s: float = 0.0,
        noise: bool = True,
        d2d_m: NDArray | None = None,
        draws: list[dict] | None = None,
        serving: NDArray[np.bool_] | None = None,
        motion=None,
    ) -> tuple[NDArray[np.complex64], int]:
        """The received burst at F_s/D (sum over RRHs in range + AWGN).

        ``serving`` [links]: the links of the serving cell (``data_beam="serving"``; none
        serving when omitted). ``motion`` (:class:`railradio.nr.channel.motion.BurstMotion`): the
        links' geometry follows the train through the burst, symbol by symbol — bulk delay
        (a per-symbol phase ramp), the LOS phase's curvature and the beam gains at each
        symbol's receive instant — instead of being held at the epoch instant (the
        production's shortcut, bounded in :mod:`railradio.nr.study.fidelity`).

        Returns ``(z, s_min)``: samples from the CP start of symbol ``s_min`` (negative:
        before the burst's first subframe).

        Parameters
        ----------
        links : Links
            The RRHs in range at the epoch.
        rng : numpy.random.Generator
            The epoch's generator (fading, beams, loads, noise).
        t0_s : float
            Time of the burst start, s.
        noise : bool
            Add the receiver's AWGN.
        d2d_m : numpy.ndarray or None
            [links] 2-D train–RRH distances, m (compared with ``full_channel_range_m``; None: all
            full channel).
        draws : list of dict or None
            The links' random draws (:meth:`draws`); None: drawn here from ``rng``.
        serving : numpy.ndarray of bool or None
            See above.
        motion : railradio.nr.channel.motion.BurstMotion or None
            See above.

        Returns
        -------
        z : numpy.ndarray of complex64
            The burst's samples at F_s/D (amplitude √W).
        s_min : int
            Symbol index of its first sample.
        """
        num = self.cfg.num
        n = num.n_fft
        fs = num.sample_rate_hz
        sp = self.span(float(np.max(links.tau_s)) if links.n else 0.0)
        symbols, total = sp["symbols"], sp["total"]
        z = np.zeros(total, dtype=np.complex64)
        t_sym = (num.symbol_start(symbols) + sp["cps"] + n / 2) / fs + t0_s
        if draws is None:
            draws = self.draws(links, rng)
        at_train = at_train_mask(self.data_beam, links, serving)
        g_syms, geo_h = symbol_gains(links, draws, at_train, sp, t_sym, motion, self.f_k)
        full = np.ones(links.n, dtype=bool) if d2d_m is None else np.asarray(d2d_m) <= self.full_channel_range_m
        self.kept_gains = {}
        self._add_links(z, links, draws, at_train, g_syms, geo_h, full, sp, t_sym, t0_s)
        if noise:
            var = links.noise_psd_w_hz * fs * links.n_chains
            # complex AWGN: interleaved (re, im) float32 draws, variance var/2 each
            z += np.float32(np.sqrt(var / 2)) * rng.standard_normal(2 * total, dtype=np.float32).view(np.complex64)
        return z, sp["s_min"]

    def _add_links(
        self,
        z: NDArray[np.complex64],
        links: Links,
        draws: list[dict],
        at_train: NDArray[np.bool_],
        g_syms: NDArray[np.float32],
        geo_h: NDArray[np.complex64] | None,
        full: NDArray[np.bool_],
        sp: dict,
        t_sym: NDArray[np.float64],
        t0_s: float,
    ) -> None:
        """Add every link's received burst (without noise) to ``z``, link by link."""
        num, prof = self.cfg.num, self.profile
        n = num.n_fft
        fs = num.sample_rate_hz
        symbols, total = sp["symbols"], sp["total"]
        # symbols synthesized: all, or with no data traffic only the SS-block symbols (the
        # others are empty; leaving them out changes the burst only by the float32 rounding
        # of a different FFT batch, tests/nr/test_simulate.py)
        rows = np.flatnonzero(sp["block_of"] >= 0) if self.data_beam == "none" else np.arange(symbols.size)
        every = rows.size == symbols.size
        x = np.empty((rows.size, n), dtype=np.complex64)
        u = np.empty_like(x) if self.exact_spill and prof.powers.size else None  # tap-less spectra
        long_of, starts, cps = (
            (sp["long_of"], sp["starts"], sp["cps"])
            if every
            else (sp["long_of"][rows], sp["starts"][rows], sp["cps"][rows])
        )
        amp_l = np.sqrt(prof.powers / self.n_sinusoids)
        # per-RRH quantities, vectorized over RRHs: delay τ0 = (n_c - ε)/F_s is placed at
        # n_c, the rest (and the CP start) is a per-symbol phase ramp: sample m of symbol s
        # is x(t_m - τ0) at m - cp_s + n_c
        n_cs = np.ceil(links.tau_s * fs - 1e-9).astype(np.int64)  # [R]
        frac = links.tau_s * fs - n_cs  # [R] in (-1, 0]
        ramps = np.exp(-2j * np.pi * np.outer(frac + sp["cp0"], self.k) / n).astype(np.complex64)  # [R, n]
        t_firsts = (num.symbol_start(sp["s_min"]) + n_cs) / fs + t0_s  # [R]
        for r in range(links.n):
            n_c = int(n_cs[r])
            if n_c >= total:
                continue
            ov = self.overlay(links.n_id1[r], links.n_id2[r])
            pool_idx, g_r = draws[r]["pool_idx"], g_syms[r]
            if not at_train[r] and self.data_beam != "none":  # an idle slot sends no data
                pool_idx = np.where(draws[r]["busy"], pool_idx, self.idle_row)
            if not every:
                ov = (ov[0][rows],) + ov[1:]
                pool_idx, g_r = pool_idx[rows], g_r[rows]
            grid = _LinkGrid(pool_idx, ov, ramps[r], g_r, long_of, sp["long_ramp"])
            gains = h = None
            if full[r] and prof.powers.size:
                gains, h = self._tap_gains(links, r, draws[r], amp_l, t_sym)
                self.kept_gains[r] = gains
            self._fill_link(x, u, grid, h, None if geo_h is None else geo_h[r], every, rows)
            y = fft_rows(x, inverse=True, out=x)
            # LOS phase e^{j(2π f t + φ0)} at receive times, applied while placing
            kernels.place(
                z, y, starts, cps, n_c, 2 * np.pi * links.f_los_hz[r], float(t_firsts[r]), links.phase0[r], 1.0 / fs
            )
            if u is not None and full[r]:
                self.spill.add(
                    z,
                    u,
                    rows,
                    every,
                    gains,
                    n_c,
                    float(links.tau_s[r]),
                    sp,
                    2 * np.pi * links.f_los_hz[r],
                    float(t_firsts[r]),
                    float(links.phase0[r]),
                )

    def _tap_gains(
        self, links: Links, r: int, draw: dict, amp_l: NDArray[np.float64], t_sym: NDArray[np.float64]
    ) -> tuple[NDArray[np.complex64], NDArray[np.complex64]]:
        """Link ``r``'s Rayleigh tap gains per symbol, relative to its LOS phase (complex64
        [S, L]), and its channel's frequency response h = gains · basis + √P_LOS [S, n]."""
        f_lm = links.doppler_hz * np.cos(draw["alpha"])
        taps = kernels.sos_taps(amp_l, f_lm, draw["phi"], t_sym)
        taps *= np.exp(-1j * (2 * np.pi * links.f_los_hz[r] * t_sym + links.phase0[r]))[:, None]
        gains = taps.astype(np.complex64)
        h = gains @ self.basis
        h += np.float32(np.sqrt(self.profile.los_power))
        return gains, h

    def _fill_link(
        self,
        x: NDArray[np.complex64],
        u: NDArray[np.complex64] | None,
        grid: _LinkGrid,
        h: NDArray[np.complex64] | None,
        geo_r: NDArray[np.complex64] | None,
        every: bool,
        rows: NDArray[np.int64],
    ) -> None:
        """Write one link's received spectra of the synthesized symbols into ``x`` (and the
        tap-less ones into ``u`` when kept): with its channel response ``h`` (``None``: a far
        interferer, one tap with the profile's total power) and its per-symbol geometry
        ``geo_r`` (``None``: held at the epoch instant)."""
        no_h = np.ones((1, 1), dtype=np.complex64)
        if h is not None:
            if u is not None:  # the tap-less spectra kept for the spill, then x = u · h
                geo = (geo_r if every else geo_r[rows]) if geo_r is not None else no_h
                self._fill_grid(u, grid, geo, geo_r is not None)
                np.multiply(u, h if every else h[rows], out=x)
            else:
                if geo_r is not None:
                    h *= geo_r
                self._fill_grid(x, grid, h if every else h[rows], True)
        elif geo_r is not None:  # far interferer, its geometry symbol by symbol
            self._fill_grid(x, grid, geo_r if every else geo_r[rows], True)
        else:  # far interferer: one tap with the profile's total power, LOS Doppler
            self._fill_grid(x, grid, no_h, False)

    def _fill_grid(self, out: NDArray[np.complex64], grid: _LinkGrid, h: NDArray[np.complex64], has_h: bool) -> None:
        """:func:`kernels.fill_grid` of one link's grid into ``out`` with the response ``h``."""
        kernels.fill_grid(
            out, self.pool_band, grid.pool_idx, *grid.ov, h, has_h, grid.ramp, grid.g_row, grid.long_of, grid.long_ramp
        )
