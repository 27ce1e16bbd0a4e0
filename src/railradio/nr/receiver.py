"""Received SS bursts and the seed's correlation receiver (seed eq. 3–9).

Synthesis (per epoch, :class:`Synthesizer`): every RRH in range sends its burst grid (PSS,
SSS, PBCH, full-buffer data; SS-block symbols on that block's beam, other symbols on their
data beam) through its own channel: bulk 3-D delay τ0 (TS 38.211's time-continuous symbols
sampled exactly: a per-symbol phase ramp e^{-j2π f_k τ0} and each symbol's extent placed at
⌈τ0 F_s⌉), TDL taps (per-symbol Rayleigh gains, fixed-delay basis e^{-j2π f_k τ_l}) and the
LOS tap's Doppler as a continuous phase within every symbol (inter-carrier interference);
plus AWGN. Its shortcuts, each measured against the exact computation
(:func:`railradio.nr.reference.reference_received`) on paper-scale epochs by the fidelity
target (:mod:`railradio.nr.fidelity`):

* a band: only the N_FFT/D_s central subcarriers are synthesized (at F_s/D_s), then the
  receiver's front end filters to its own band;
* the Rayleigh taps are held per symbol and rotate within a symbol with the LOS Doppler;
  each delayed tap's copy of a symbol is wrapped within the symbol's extent (its spill into
  the next symbol is omitted);
* the geometry (bulk delay, LOS Doppler, beam gains) is held over the 2 ms burst (the train
  moves ≤ 0.26 m, 0.2 full-rate samples); ``motion`` follows it symbol by symbol.

Correlation (:class:`Correlator`): one FFT window per SS block (lags 0..K-1 plus the
reference length), R = IFFT(Z·conj(B)) on the receiver's lag grid for the detection
statistics (μ_i, σ_i over the window), and band-limited evaluation at full-rate integer lags
around the peaks for η_i and the TOA (seed eq. 9 is an argmax over full-rate samples). The
lag grid may be finer than the front end's samples (``template_decimation``): the samples
band-limited-interpolated, the template zero-stuffed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.fft as sfft
from numpy.typing import NDArray

from railradio.nr import kernels
from railradio.nr.channel import TdlProfile, sos_params
from railradio.nr.numerology import N_FFT, SUBCARRIER_SPACING_HZ, SYMBOLS_PER_SLOT, Numerology, ssb_first_symbols
from railradio.nr.ssb import band_bins, burst_grid, reference_waveform


def fft_rows(a: NDArray[np.complex64], inverse: bool = False, out: NDArray | None = None) -> NDArray[np.complex64]:
    """FFT (or the 1/N-normalized inverse, as ``numpy.fft.ifft``) of each row of ``a``
    [..., N], on one thread, with ``scipy.fft`` (pocketfft, compiled for the wheel's
    baseline instruction set: the result does not depend on the CPU's vector unit).
    ``out``, when given, receives the result (it may be ``a`` itself)."""
    f = sfft.ifft if inverse else sfft.fft
    y = f(a, axis=-1, workers=1, overwrite_x=out is a)
    if out is None:
        return y
    if y.ctypes.data != out.ctypes.data:  # overwrite_x already wrote into ``a``'s buffer
        out[...] = y
    return out


@dataclass(frozen=True)
class ReceiverConfig:
    """Receiver and burst settings.

    Parameters
    ----------
    decimation
        D: synthesize and correlate at F_s/D (1, 2, 4 or 8).
    ssb_pattern, n_blocks
        SS-block positions (``seed`` or ``caseE``) and blocks per burst (seed: 64).
    search_lags
        K, correlation lags per block at the full rate; ``None``: the minimum spacing of
        SS blocks (seed eq. 5).
    detect_k_sigma
        Detection threshold η > μ + kσ (seed eq. 6: 4).
    n_aod_blocks
        Blocks averaged for the AOD (seed eq. 7: 3).
    subsample
        Parabolic sub-sample TOA interpolation [ours; off for the reproduction].
    """

    decimation: int = 4
    ssb_pattern: str = "seed"
    n_blocks: int = 64
    search_lags: int | None = None
    detect_k_sigma: float = 4.0
    n_aod_blocks: int = 3
    subsample: bool = False
    prescreen_k_sigma: float = 3.0
    template: str = "pss_sss"
    """Correlation reference: PSS + SSS (seed) or SSS only [ours]."""
    toa_blocks: int | None = None
    """TOA combining (eq. 8) over all detected blocks (``None``, the seed) or over the
    ``toa_blocks`` detected blocks with the largest (η - μ)/σ [ours]."""

    def __post_init__(self) -> None:
        Numerology(self.decimation)
        ssb_first_symbols(self.ssb_pattern, self.n_blocks)
        if self.search_lags is not None and self.search_lags < 1:
            raise ValueError(f"search_lags must be >= 1, got {self.search_lags!r}")
        if not self.detect_k_sigma > 0:
            raise ValueError("detect_k_sigma must be > 0")

    @cached_property
    def num(self) -> Numerology:
        return Numerology(self.decimation)

    @cached_property
    def ssb_first(self) -> NDArray[np.int64]:
        return ssb_first_symbols(self.ssb_pattern, self.n_blocks)

    @cached_property
    def block_start_full(self) -> NDArray[np.int64]:
        """v_i: first full-rate sample of each block (CP start of its symbol 0)."""
        return Numerology(1).symbol_start(self.ssb_first)

    @cached_property
    def lags_full(self) -> int:
        """K [full-rate samples]."""
        if self.search_lags is not None:
            return int(self.search_lags)
        return int(np.min(np.diff(self.block_start_full))) if self.n_blocks > 1 else 6576

    @cached_property
    def lags(self) -> int:
        """K at the decimated rate."""
        return -(-self.lags_full // self.decimation)


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
        return int(self.tau_s.size)


DATA_BEAMS = ("serving", "train", "random", "none")


class Synthesizer:
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
        self.cfg, self.profile = cfg, profile
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
        # the taps' spill (kernels.add_spill): tap l's copy of a symbol begins at most
        # ⌈τ_l F⌉ samples into its slot; column col_of[l, j] of ``spill_at`` evaluates a
        # symbol's waveform at sample j - τ_l F (e^{j2π k (j - τ_l F)/n}/n, as the IFFT)
        fs = num.sample_rate_hz
        reach = np.ceil(profile.delays_s * fs - 1e-9).astype(np.int64)
        self.spill_reach = reach
        self.spill_col_of = np.zeros((reach.size, int(reach.max(initial=0))), dtype=np.int64)
        cols = []
        for l, r in enumerate(reach):
            for j in range(r):
                self.spill_col_of[l, j] = len(cols)
                cols.append(j - profile.delays_s[l] * fs)
        self.spill_at = (np.exp(2j * np.pi * np.outer(self.k, cols) / n) / n).astype(np.complex64)  # [n, Q]
        self._overlays: dict = {}
        self._span: tuple | None = None

    def span(self, max_tau_s: float) -> dict:
        """Symbol layout covering delays up to ``max_tau_s`` (cached by pre-burst length)."""
        cfg, num = self.cfg, self.cfg.num
        n = num.n_fft
        num1 = Numerology(1)
        n_pre = int(np.ceil(max_tau_s * num1.sample_rate_hz / (N_FFT + 72))) + 1
        if self._span is not None and self._span["n_pre"] >= n_pre:
            return self._span
        n_pre = max(n_pre, 4)
        last_needed = (
            cfg.block_start_full[-1] + cfg.lags_full + len(reference_waveform(num1, 0, 0, int(cfg.ssb_first[-1])))
        )
        s_end = int(cfg.ssb_first[-1])
        while num1.symbol_start(s_end) < last_needed:
            s_end += 1
        symbols = np.arange(-n_pre, s_end + 1)
        cps = num.cp_length(symbols)
        starts = num.symbol_start(symbols) - num.symbol_start(symbols[0])
        total = int(starts[-1] + n + cps[-1])
        # read-out (kernels.place): symbol s occupies n + cp_s samples read cyclically from
        # its IFFT output y_s (0..n-1 then 0..cp_s-1); the CP and the placement offset are
        # folded into the subcarrier phase ramp
        # SS-block symbol -> block index
        block_of = np.full(symbols.size, -1, dtype=np.int64)
        first_pos = {int(sv): i for i, sv in enumerate(symbols)}
        for b, f in enumerate(cfg.ssb_first):
            for off in range(4):
                if int(f) + off in first_pos:
                    block_of[first_pos[int(f) + off]] = b
        cp0 = int(num.cp_length(1))
        long_rows = np.flatnonzero(cps != cp0)
        long_ramp = np.exp(-2j * np.pi * np.outer(cps[long_rows] - cp0, np.fft.fftfreq(n, 1.0 / n)) / n).astype(
            np.complex64
        )
        long_of = np.full(symbols.size, -1, dtype=np.int64)
        long_of[long_rows] = np.arange(long_rows.size)
        slot = symbols // SYMBOLS_PER_SLOT
        slot = slot - slot[0]  # each symbol's slot, 0-based
        self._span = dict(
            n_pre=n_pre,
            symbols=symbols,
            slot=slot,
            cps=np.ascontiguousarray(cps, dtype=np.int64),
            starts=np.ascontiguousarray(starts, dtype=np.int64),
            total=total,
            cp0=cp0,
            long_of=long_of,
            long_ramp=long_ramp,
            block_of=block_of,
            s_min=int(symbols[0]),
        )
        self._overlays.clear()
        return self._span

    def overlay(self, n_id1: int, n_id2: int) -> tuple[NDArray, ...]:
        """Where and what the cell's SS blocks write over the pool data, compact (cached per
        cell): ``(ov_row [symbols], ov_full, ov_mask, ov_val)`` as :func:`kernels.fill_grid`
        takes them — the overlay row of each symbol (-1: none), whether it covers the whole
        band, and its mask and values."""
        key = (int(n_id1), int(n_id2))
        if key not in self._overlays:
            sp = self._span
            num = self.cfg.num
            marked, _ = burst_grid(
                num,
                sp["symbols"],
                self.cfg.ssb_first,
                *key,
                np.full((1, N_FFT), np.nan + 0j, dtype=np.complex64),
                np.zeros(sp["symbols"].size, dtype=np.int64),
            )
            mask = ~np.isnan(marked.real) & (sp["block_of"][:, None] >= 0)
            rows = np.flatnonzero(mask.any(axis=1))
            ov_row = np.full(mask.shape[0], -1, dtype=np.int64)
            ov_row[rows] = np.arange(rows.size)
            ov_mask = np.ascontiguousarray(mask[rows])
            ov_val = np.ascontiguousarray(np.where(ov_mask, marked[rows], 0).astype(np.complex64))
            self._overlays[key] = (ov_row, ov_mask.all(axis=1), ov_mask, ov_val)
        return self._overlays[key]

    def draws(self, links: Links, rng: np.random.Generator) -> list[dict]:
        """The random draws of one burst per RRH: data pool indices, fading (α, φ), and per
        slot the beam and whether the slot carries data (used by non-serving RRHs)."""
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

    def _add_spill(self, z, u, rows, every, gains, n_c, tau0_s, sp, w_rad_s, t_first_s, phase0_rad) -> None:
        """Add the delayed taps' spill across symbol boundaries, which the cyclic read-out of
        each symbol's IFFT (:func:`kernels.place`) leaves out: the first b_l samples of a
        symbol's slot carry tap l's copy of the previous symbol, not of its own cyclic
        extension. With Δ_s = u_{s-1} e^{j2π k cp_{s-1}/n} - u_s (the tap-less spectra; a
        symbol not synthesized is empty), the correction at sample j of slot s is
        Σ_{l: j < b_l} g_{s,l} δ_s(j - τ_l F), δ_s the IFFT of Δ_s evaluated off the grid:
        one matrix product with :attr:`spill_at`. Exact (``tests/nr/test_fidelity.py``: the
        fast path equals the exact reference's per-symbol taps to float32 rounding). b_l uses
        the epoch's delay τ0 (under ``motion`` a symbol's edge moves by < 0.05 sample)."""
        num, n = self.cfg.num, self.cfg.num.n_fft
        fs = num.sample_rate_hz
        u_all = u if every else np.zeros((sp["symbols"].size, n), dtype=np.complex64)
        if not every:
            u_all[rows] = u
        if "cp_turn" not in sp:  # e^{j2π k cp_s/n} per symbol, cached with the layout
            cps, inv = np.unique(sp["cps"][:-1], return_inverse=True)
            sp["cp_turn"] = np.exp(2j * np.pi * np.outer(cps, self.k) / n).astype(np.complex64)[inv]
        cp_turn = sp["cp_turn"]
        delta = np.empty_like(u_all)
        np.multiply(u_all[:-1], cp_turn, out=delta[1:])
        delta[0] = 0
        delta -= u_all
        b = np.ceil((tau0_s + self.profile.delays_s) * fs - 1e-9).astype(np.int64) - n_c
        b = np.clip(b, 0, self.spill_reach)
        kernels.add_spill(
            z,
            delta @ self.spill_at,
            self.spill_col_of,
            b,
            gains,
            sp["starts"],
            n_c,
            w_rad_s,
            t_first_s,
            phase0_rad,
            1.0 / fs,
        )

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
        serving when omitted). ``motion`` (:class:`railradio.nr.motion.BurstMotion`): the
        links' geometry follows the train through the burst, symbol by symbol — bulk delay
        (a per-symbol phase ramp), the LOS phase's curvature and the beam gains at each
        symbol's receive instant — instead of being held at the epoch instant (the
        production's shortcut, bounded in :mod:`railradio.nr.fidelity`).

        Returns ``(z, s_min)``: samples from the CP start of symbol ``s_min`` (negative:
        before the burst's first subframe).
        """
        num, prof = self.cfg.num, self.profile
        n = num.n_fft
        fs = num.sample_rate_hz
        sp = self.span(float(np.max(links.tau_s)) if links.n else 0.0)
        symbols, total = sp["symbols"], sp["total"]
        z = np.zeros(total, dtype=np.complex64)
        t_sym = (num.symbol_start(symbols) + sp["cps"] + n / 2) / fs + t0_s
        if draws is None:
            draws = self.draws(links, rng)
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
        no_h = np.ones((1, 1), dtype=np.complex64)
        amp_l = np.sqrt(prof.powers / self.n_sinusoids)
        # per-RRH quantities, vectorized over RRHs: delay τ0 = (n_c - ε)/F_s is placed at
        # n_c, the rest (and the CP start) is a per-symbol phase ramp: sample m of symbol s
        # is x(t_m - τ0) at m - cp_s + n_c
        n_cs = np.ceil(links.tau_s * fs - 1e-9).astype(np.int64)  # [R]
        frac = links.tau_s * fs - n_cs  # [R] in (-1, 0]
        ramps = np.exp(-2j * np.pi * np.outer(frac + sp["cp0"], self.k) / n).astype(np.complex64)  # [R, n]
        is_ss = sp["block_of"] >= 0
        ss_amp = links.beam_amp[:, np.maximum(sp["block_of"], 0)]  # [R, S]
        at_train = np.zeros(links.n, dtype=bool)  # links whose data go toward the train
        if self.data_beam == "train":
            at_train[:] = True
        elif self.data_beam == "serving" and serving is not None:
            at_train[:] = np.asarray(serving, dtype=bool)
        data_amp = np.empty(ss_amp.shape)
        for r in range(links.n):  # "none": the data are zero anyway (zero pool)
            data_amp[r] = links.data_amp[r] if at_train[r] else links.beam_amp[r][draws[r]["data_beam"]]
        geo_h = None
        if motion is not None:  # per-symbol geometry at each symbol's receive instant
            t_rx = t_sym[None, :] + links.tau_s[:, None]  # [R, S]
            ba_t = motion.beam_amp(t_rx)  # [R, S, B]
            beam = np.empty(ss_amp.shape, dtype=np.int64)
            for r in range(links.n):
                b_data = (
                    np.full(symbols.size, int(np.argmin(np.abs(links.beam_amp[r] - links.data_amp[r]))))
                    if at_train[r]
                    else draws[r]["data_beam"]
                )
                beam[r] = np.where(is_ss, np.maximum(sp["block_of"], 0), b_data)
            ss_amp = data_amp = np.take_along_axis(ba_t, beam[:, :, None], axis=2)[:, :, 0]
            d_tau = motion.delay_s(t_rx) - links.tau_s[:, None]  # [R, S]
            geo_h = np.exp(
                1j
                * (motion.phase_excess_rad(t_rx)[:, :, None] - 2 * np.pi * d_tau[:, :, None] * self.f_k[None, None, :])
            ).astype(np.complex64)
        g_syms = (np.where(is_ss[None, :], ss_amp, data_amp) * (links.amp * n)[:, None]).astype(
            np.float32
        )  # × n: unnormalized IFFT
        t_firsts = (num.symbol_start(sp["s_min"]) + n_cs) / fs + t0_s  # [R]
        full = np.ones(links.n, dtype=bool) if d2d_m is None else np.asarray(d2d_m) <= self.full_channel_range_m
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
            if full[r] and prof.powers.size:
                f_lm = links.doppler_hz * np.cos(draws[r]["alpha"])
                taps = kernels.sos_taps(amp_l, f_lm, draws[r]["phi"], t_sym)
                taps *= np.exp(-1j * (2 * np.pi * links.f_los_hz[r] * t_sym + links.phase0[r]))[:, None]
                gains = taps.astype(np.complex64)
                h = gains @ self.basis
                h += np.float32(np.sqrt(prof.los_power))
                if u is not None:  # the tap-less spectra kept for the spill, then x = u · h
                    geo = (geo_h[r] if every else geo_h[r][rows]) if geo_h is not None else no_h
                    kernels.fill_grid(
                        u,
                        self.pool_band,
                        pool_idx,
                        *ov,
                        geo,
                        geo_h is not None,
                        ramps[r],
                        g_r,
                        long_of,
                        sp["long_ramp"],
                    )
                    np.multiply(u, h if every else h[rows], out=x)
                else:
                    if geo_h is not None:
                        h *= geo_h[r]
                    kernels.fill_grid(
                        x,
                        self.pool_band,
                        pool_idx,
                        *ov,
                        h if every else h[rows],
                        True,
                        ramps[r],
                        g_r,
                        long_of,
                        sp["long_ramp"],
                    )
            elif geo_h is not None:  # far interferer, its geometry symbol by symbol
                kernels.fill_grid(
                    x,
                    self.pool_band,
                    pool_idx,
                    *ov,
                    geo_h[r] if every else geo_h[r][rows],
                    True,
                    ramps[r],
                    g_r,
                    long_of,
                    sp["long_ramp"],
                )
            else:  # far interferer: one tap with the profile's total power, LOS Doppler
                kernels.fill_grid(
                    x, self.pool_band, pool_idx, *ov, no_h, False, ramps[r], g_r, long_of, sp["long_ramp"]
                )
            y = fft_rows(x, inverse=True, out=x)
            # LOS phase e^{j(2π f t + φ0)} at receive times, applied while placing
            kernels.place(
                z, y, starts, cps, n_c, 2 * np.pi * links.f_los_hz[r], float(t_firsts[r]), links.phase0[r], 1.0 / fs
            )
            if u is not None and full[r]:
                self._add_spill(
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
        if noise:
            var = links.noise_psd_w_hz * fs * links.n_chains
            # complex AWGN: interleaved (re, im) float32 draws, variance var/2 each
            z += np.float32(np.sqrt(var / 2)) * rng.standard_normal(2 * total, dtype=np.float32).view(np.complex64)
        return z, sp["s_min"]


@dataclass
class BlockCorrelation:
    """Per-candidate, per-block correlation statistics of one burst.

    Shapes: [n_cand, n_blocks] unless noted. ``corr`` [n_cand, n_blocks, K_d] is the
    decimated-rate |r̃_i[k]| (kept only when requested).
    """

    eta: NDArray[np.float64]
    mu: NDArray[np.float64]
    sigma: NDArray[np.float64]
    detected: NDArray[np.bool_]
    toa_samples: NDArray[np.float64]  # [n_cand] full-rate lag δ̂ (nan: nothing detected)
    aod_rad: NDArray[np.float64]  # [n_cand] (nan: nothing detected)
    peak_comb: NDArray[np.float64]  # [n_cand] max of the combined correlation
    corr: NDArray[np.float32] | None = None


DETECTORS = ("seed", "cfar", "cacfar")
CA_WINDOW_FULL = 512
"""The CA-CFAR's reference lags on each side [full-rate lags, 2.08 µs]: the two sides span
4.2 µs, just under one OFDM symbol (4.46 µs), over which the level of the data interference
stays put (64 lags at F_s/8) [ours]."""
CA_PRESCREEN = 0.8
"""The CFAR detectors evaluate a block's peak at full-rate lags when its value on the lag
grid exceeds this share of the threshold: on the F_s/2 grid a band-limited peak falls at most
1 - sinc(1/8) = 2.5 % between grid lags (0.8 keeps a margin for the floor's own change) [ours]."""
CA_GUARD_FULL = 32
"""Guard lags on each side of the tested lag [full-rate lags, 130 ns]: the correlation's
main lobe (±1 lag at F_s/8) and TDL-D's taps within 1.8 delay spreads (36 ns), which hold all
but 0.5 % of its power (4 lags at F_s/8) [ours]."""


def cfar_threshold(window_s: float, pfa: float, n_sc: int = 127) -> float:
    """t with T sqrt(2π) β_rms t exp(-t²/2) = P_fa (Rice's envelope up-crossing rate), in
    units of the Rayleigh parameter σ_R; β_rms = Δf sqrt((n_sc² - 1)/12) [Hz]."""
    from scipy.optimize import brentq

    beta = SUBCARRIER_SPACING_HZ * np.sqrt((n_sc**2 - 1) / 12)
    c = window_s * np.sqrt(2 * np.pi) * beta

    def f(t: float) -> float:
        return np.log(c * t) - t * t / 2 - np.log(pfa)

    return float(brentq(f, 1.0, 50.0))


class Correlator:
    """The seed's correlation receiver for a set of candidate cells (seed eq. 4–9).

    Detection rule ``detector``: ``"seed"`` η_i > μ_i + kσ_i (seed eq. 6, k = 4);
    ``"cacfar"`` [ours] the seed's test and a cell-averaging CFAR test (the peak against the
    mean of the ``ca_window`` lags on each side, beyond ``ca_guard``, scaled like ``cfar``):
    robust to the data interference whose level varies across the window; or
    ``"cfar"`` [ours] η_i > t · μ_i / sqrt(π/2): on noise the correlation magnitude is a
    Rayleigh envelope (μ = σ_R sqrt(π/2)) whose expected number of up-crossings of t·σ_R
    over the window T = K/F_s is T sqrt(2π) β_rms t e^{-t²/2} (Rice, 1945), with β_rms the
    RMS bandwidth of the 127-subcarrier reference, Δf sqrt((127² - 1)/12); t solves that
    number = P_fa, the false-alarm probability per block.
    """

    def __init__(
        self,
        cfg: ReceiverConfig,
        detector: str = "seed",
        pfa: float = 1e-3,
        ca_window: int | None = None,
        ca_guard: int | None = None,
        template_decimation: int | None = None,
    ):
        """``ca_window``, ``ca_guard``: the CA-CFAR's reference lags on each side and guard
        lags at this correlator's rate (default: :data:`CA_WINDOW_FULL` and
        :data:`CA_GUARD_FULL` full-rate lags). ``template_decimation``: the rate F_s/D_t of
        the receiver's front end when the correlation runs faster than it (the reference
        waveform is built at F_s/D_t and band-limited-interpolated to ``cfg``'s rate: the
        correlation is then the band-limited interpolation of the front end's own)."""
        if detector not in DETECTORS:
            raise ValueError(f"detector must be one of {DETECTORS}, got {detector!r}")
        d = cfg.decimation
        td = d if template_decimation is None else int(template_decimation)
        if td < d or td % d:
            raise ValueError(
                f"template_decimation must be a multiple of the decimation {d}, got {template_decimation!r}"
            )
        self.template_decimation = td
        self.ca_window = CA_WINDOW_FULL // d if ca_window is None else int(ca_window)
        self.ca_guard = CA_GUARD_FULL // d if ca_guard is None else int(ca_guard)
        self.ca_prescreen = CA_PRESCREEN
        if not 0 < pfa < 1:
            raise ValueError(f"pfa must be in (0, 1), got {pfa!r}")
        self.cfg, self.detector, self.pfa = cfg, detector, pfa
        b0 = self._template(0, 0, "pss_sss")
        self.ref_len = len(b0)
        self.n_win = sfft.next_fast_len(cfg.lags + self.ref_len - 1)
        self._spectra: dict[tuple[int, int], NDArray[np.complex64]] = {}
        self.freqs = np.fft.fftfreq(self.n_win, 1.0 / self.n_win)
        # e^{j2π f δ/N} for the full-rate offsets δ = -1 ... +1 (decimated units, step 1/D)
        self.offsets_full = np.arange(-d, d + 1)  # full-rate samples
        self.offsets = self.offsets_full / d
        theta = 2 * np.pi * np.outer(self.offsets[d:], self.freqs) / self.n_win  # δ >= 0: [d + 1, N]
        # [N, 2(d + 1)]: cos θ | sin θ, the right-hand factor of kernels.at_offsets
        self.offset_cs_t = np.ascontiguousarray(np.concatenate([np.cos(theta), np.sin(theta)]).T.astype(np.float32))
        self.roots = np.exp(2j * np.pi * np.arange(self.n_win) / self.n_win).astype(np.complex64)
        self.cfar_factor = cfar_threshold(cfg.lags_full / Numerology(1).sample_rate_hz, pfa) / np.sqrt(np.pi / 2)

    def _template(self, n_id1: int, n_id2: int, template: str) -> NDArray[np.complex64]:
        """The reference waveform b at the correlation rate. Built at the front end's rate
        F_s/D_t and zero-stuffed to this one: on a burst interpolated from the front end's
        samples (:func:`railradio.nr.resample.upsample`) the correlation at lag λ is then
        Σ_n b*[n] z(n + λ) with z band-limited-interpolated, exactly the front end's own
        correlation at integer lags and its band-limited interpolation between them."""
        td, d = self.template_decimation, self.cfg.decimation
        b = reference_waveform(Numerology(td), n_id1, n_id2, int(self.cfg.ssb_first[0]), template)
        if td == d:
            return b
        f = td // d
        out = np.zeros((b.size - 1) * f + 1, dtype=np.complex64)
        out[::f] = b
        return out

    def spectrum(self, n_id1: int, n_id2: int) -> NDArray[np.complex64]:
        """conj(B): the conjugate reference spectrum of a cell, n_win bins."""
        key = (int(n_id1), int(n_id2))
        if key not in self._spectra:
            b = self._template(*key, self.cfg.template)
            self._spectra[key] = np.conj(sfft.fft(b, self.n_win)).astype(np.complex64)
        return self._spectra[key]

    def _at_offsets(
        self, p: NDArray[np.complex64], rows: NDArray[np.int64], k0: NDArray[np.int64]
    ) -> NDArray[np.float64]:
        """|c(k0 + δ)| for δ in ``self.offsets`` from the rows ``rows`` of the cross-spectra
        p [M, N] (band-limited evaluation: c(λ) = (1/N) Σ_f p[f] e^{j2π f λ/N})."""
        return kernels.at_offsets(
            p, np.asarray(k0, dtype=np.int64), self.roots, self.offset_cs_t, np.asarray(rows, dtype=np.int64)
        )

    def window_spectra(self, z: NDArray[np.complex64], s_min: int) -> NDArray[np.complex64]:
        """FFT of the received burst over each SS block's window (v_i ... v_i + N - 1),
        [n_blocks, N]; receivers with the same window length can share it."""
        num = self.cfg.num
        v = num.symbol_start(self.cfg.ssb_first) - num.symbol_start(s_min)  # [B]
        idx = v[:, None] + np.arange(self.n_win)[None, :]
        zw = np.zeros((len(v), self.n_win), dtype=np.complex64)
        ok = idx < z.size
        zw[ok] = z[idx[ok]]
        return fft_rows(zw, out=zw)

    def correlate(
        self,
        z: NDArray[np.complex64],
        s_min: int,
        n_id1: NDArray,
        n_id2: NDArray,
        keep_corr: bool = False,
        zf: NDArray[np.complex64] | None = None,
    ) -> BlockCorrelation:
        """Per-block correlation, detection, AOD and TOA of the candidate cells (seed eq. 4–9).

        ``zf``: the burst's :meth:`window_spectra`, when already computed for ``z``.
        """
        cfg = self.cfg
        d = cfg.decimation
        if zf is None:
            zf = self.window_spectra(z, s_min)  # [B, N]
        n_c = len(n_id1)
        n_b = zf.shape[0]
        bspec = np.stack([self.spectrum(a, b) for a, b in zip(n_id1, n_id2, strict=True)])  # [C, N]
        p = np.empty((n_c, n_b, self.n_win), dtype=np.complex64)
        kernels.cross_spectra(np.ascontiguousarray(zf, dtype=np.complex64), bspec, p)  # [C, B, N]
        p2 = p.reshape(n_c * n_b, self.n_win)  # row c·B + b
        # one candidate at a time: its IFFT and the pass over |r| stay in cache
        r = np.empty((n_c, n_b, cfg.lags), dtype=np.float32)
        mu, sigma, eta = (np.empty((n_c, n_b)) for _ in range(3))
        k_lo = np.empty((n_c, n_b), dtype=np.int64)
        for c in range(n_c):
            xc = fft_rows(p[c], inverse=True)
            r[c], mu[c], sigma[c], eta[c], k_lo[c] = kernels.magnitude_stats(xc, cfg.lags)
        if self.detector == "cacfar":  # [ours] local noise floor per lag
            k_lo, eta, floor_at = (
                a.reshape(n_c, n_b)
                for a in kernels.local_mean_argmax(r.reshape(n_c * n_b, cfg.lags), self.ca_window, self.ca_guard)
            )
            # both tests: the seed's μ + kσ over the window and the local CFAR test
            threshold = np.maximum(floor_at * self.cfar_factor, mu + cfg.detect_k_sigma * sigma)
            pre = threshold * self.ca_prescreen
        elif self.detector == "cfar":
            threshold = mu * self.cfar_factor
            pre = threshold * self.ca_prescreen
        else:
            threshold = mu + cfg.detect_k_sigma * sigma
            pre = mu + cfg.prescreen_k_sigma * sigma
        cand = eta > pre
        pre_row = np.full((n_c, n_b), -1, dtype=np.int64)  # row of pre_vals, evaluated at k_lo
        pre_vals = np.zeros((0, self.offsets.size))
        if d > 1 and np.any(cand):  # η at full-rate lags around promising peaks
            ci, bi = np.nonzero(cand)
            pre_vals = self._at_offsets(p2, ci * n_b + bi, k_lo[ci, bi])
            pre_row[ci, bi] = np.arange(ci.size)
            eta[ci, bi] = np.maximum(eta[ci, bi], pre_vals.max(axis=1))
        detected = eta > threshold
        toa = np.full(n_c, np.nan)
        aod = np.full(n_c, np.nan)
        peak = np.zeros(n_c)
        for c in range(n_c):
            det = np.flatnonzero(detected[c])
            if det.size == 0:
                continue
            if cfg.toa_blocks is not None:  # [ours] the most significant detected blocks
                score = (eta[c, det] - mu[c, det]) / sigma[c, det]
                det = det[np.argsort(score)[::-1][: cfg.toa_blocks]]
            comb = r[c, det].sum(axis=0)  # seed eq. 8 (decimated lags)
            kc = int(comb.argmax())
            if d > 1:  # eq. 9 at full-rate lags d·kc - d ... d·kc + d
                # blocks whose own peak lag is kc were evaluated there already
                rows = pre_row[c, det]
                hit = (rows >= 0) & (k_lo[c, det] == kc)
                each = np.empty((det.size, self.offsets.size))
                each[hit] = pre_vals[rows[hit]]
                if not hit.all():
                    each[~hit] = self._at_offsets(p2, c * n_b + det[~hit], np.full(int((~hit).sum()), kc))
                vals = each.sum(axis=0)
                full = d * kc + self.offsets_full
            else:
                full = np.arange(max(kc - 1, 0), min(kc + 2, cfg.lags))
                vals = comb[full]
            okl = (full >= 0) & (full < cfg.lags_full)
            vals, full = vals[okl], full[okl]
            j = int(vals.argmax())
            delta = float(full[j])
            if cfg.subsample and 0 < j < len(full) - 1:
                y0, y1, y2 = vals[j - 1], vals[j], vals[j + 1]
                den = y0 - 2 * y1 + y2
                if den < 0:
                    delta += 0.5 * (y0 - y2) / den
            toa[c] = delta
            peak[c] = float(vals[j])
            det = np.flatnonzero(detected[c])
            top = det[np.argsort(eta[c, det])[::-1][: cfg.n_aod_blocks]]  # seed eq. 7
            w = eta[c, top] / eta[c, top].sum()
            aod[c] = float(np.sum(w * self.beam_angles[top]))
        return BlockCorrelation(eta, mu, sigma, detected, toa, aod, peak, r.astype(np.float32) if keep_corr else None)

    @cached_property
    def beam_angles(self) -> NDArray[np.float64]:
        k = np.arange(self.cfg.n_blocks)
        return -np.radians((k + 0.5) * 180.0 / self.cfg.n_blocks)
