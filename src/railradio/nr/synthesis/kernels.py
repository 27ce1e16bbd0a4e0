"""Compiled inner loops of the nr synthesizer and correlator (numba).

Each kernel fuses what would otherwise be several full passes of NumPy temporaries over a
burst-sized array; the NumPy formulation each one replaces is stated in its docstring and
checked against it in ``tests/nr/test_kernels.py``. No kernel changes the model.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_TWO_PI = 2.0 * np.pi


@njit(cache=True, nogil=True)
def sos_taps(amp_l: np.ndarray, f_lm_hz: np.ndarray, phi_lm: np.ndarray, t_s: np.ndarray) -> np.ndarray:
    """Sum-of-sinusoids tap gains a_l(t_s) = amp_l Σ_m e^{j(2π f_lm t_s + φ_lm)}, [S, L].

    Phasor recursion over increasing times in complex128 (the rotation recomputed when the
    time step changes by more than 1 ps), re-anchored exactly every 32 steps; equals
    ``amp_l[None, :] * railradio.nr.channel.tdl.sos_eval(...)`` sums to ~1e-13.

    Parameters
    ----------
    amp_l : numpy.ndarray
        Per-tap amplitude √(P_l / M) [√linear]: [L].
    f_lm_hz : numpy.ndarray
        Sinusoid frequencies f_D cos α_lm [Hz]: [L, M].
    phi_lm : numpy.ndarray
        Sinusoid phases [rad]: [L, M].
    t_s : numpy.ndarray
        Evaluation times [s], increasing: [S].

    Returns
    -------
    numpy.ndarray of complex128
        Tap gains a_l(t_s) [√linear]: [S, L].
    """
    n_t = t_s.size
    n_l, n_m = f_lm_hz.shape
    w = (_TWO_PI * f_lm_hz).ravel()
    phi = phi_lm.ravel()
    ph = np.empty(w.size, dtype=np.complex128)
    rot = np.empty(w.size, dtype=np.complex128)
    out = np.empty((n_t, n_l), dtype=np.complex128)
    prev_dt = np.nan
    for s in range(n_t):
        if s % 32 == 0:
            for i in range(w.size):
                ph[i] = np.exp(1j * (w[i] * t_s[s] + phi[i]))
        else:
            dt = t_s[s] - t_s[s - 1]
            if not abs(dt - prev_dt) <= 1e-12:  # a new step (not time rounding, ~1e-13 s)
                for i in range(w.size):
                    rot[i] = np.exp(1j * w[i] * dt)
                prev_dt = dt
            for i in range(w.size):
                ph[i] = ph[i] * rot[i]
        for l in range(n_l):
            acc = 0j
            for m in range(n_m):
                acc += ph[l * n_m + m]
            out[s, l] = amp_l[l] * acc
    return out


@njit(cache=True, nogil=True)
def fill_grid(
    x: np.ndarray,
    pool: np.ndarray,
    pool_idx: np.ndarray,
    ov_row: np.ndarray,
    ov_full: np.ndarray,
    ov_mask: np.ndarray,
    ov_val: np.ndarray,
    h: np.ndarray,
    has_h: bool,
    ramp: np.ndarray,
    g_row: np.ndarray,
    long_of: np.ndarray,
    long_ramp: np.ndarray,
) -> None:
    """x[s, k] = src[s, k] · h[s, k] · ramp[k] · g_row[s] · long_ramp[long_of[s], k], in place.

    src[s, k] is the data-pool symbol ``pool[pool_idx[s], k]`` unless row s carries the
    cell's SS-block overlay (``o = ov_row[s] >= 0``): then ``ov_val[o, k]`` where
    ``ov_mask[o, k]`` (every k when ``ov_full[o]``). The overlay is compact — only its rows
    — so that the grids of the twenty-odd cells of a burst stay in cache. ``h`` is ignored
    unless ``has_h`` (flat channel); ``long_of[s] < 0`` means no long-CP ramp for that row.
    NumPy form, with the dense mask M and values V (M[s] = ov_mask[ov_row[s]], V alike):
    ``grid = pool[pool_idx]; grid[M] = V[M]; x = grid * h * ramp * g[:, None]; x[long] *= long_ramp``.

    Parameters
    ----------
    x : numpy.ndarray of complex64
        Output, overwritten: the symbols' received spectra [S, n] (reduced-FFT bin order).
    pool : numpy.ndarray of complex64
        Data pool over the synthesized band [P, n], unit EPRE.
    pool_idx : numpy.ndarray of int64
        Pool row of each symbol: [S].
    ov_row : numpy.ndarray of int64
        Overlay row of each symbol, -1 for none: [S].
    ov_full : numpy.ndarray of bool
        Whether an overlay row covers every bin: [O].
    ov_mask : numpy.ndarray of bool
        Bins an overlay row writes: [O, n].
    ov_val : numpy.ndarray of complex64
        The overlay's values (PSS, SSS and the zeroed subcarriers around them; 0 outside
        ``ov_mask``): [O, n]. The PBCH is not in it: it comes from the data pool.
    h : numpy.ndarray of complex64
        Channel response per symbol and bin [S, n] (read only when ``has_h``).
    has_h : bool
        Apply ``h``.
    ramp : numpy.ndarray of complex64
        The link's delay and CP phase ramp per bin: [n].
    g_row : numpy.ndarray of float32
        Amplitude per symbol (× n for the unnormalized IFFT) [√W]: [S].
    long_of : numpy.ndarray of int64
        Row of ``long_ramp`` for each symbol, -1 for none: [S].
    long_ramp : numpy.ndarray of complex64
        Extra phase ramps of the long-CP symbols: [n_long, n].
    """
    n_s, n = x.shape
    f = np.empty(n, dtype=np.complex64)
    for s in range(n_s):
        p = pool_idx[s]
        lr = long_of[s]
        gs = g_row[s]
        o = ov_row[s]
        for k in range(n):
            f[k] = ramp[k] * gs
        if has_h:
            for k in range(n):
                f[k] *= h[s, k]
        if lr >= 0:
            for k in range(n):
                f[k] *= long_ramp[lr, k]
        if o < 0:
            for k in range(n):
                x[s, k] = pool[p, k] * f[k]
        elif ov_full[o]:
            for k in range(n):
                x[s, k] = ov_val[o, k] * f[k]
        else:
            for k in range(n):
                v = ov_val[o, k] if ov_mask[o, k] else pool[p, k]
                x[s, k] = v * f[k]


@njit(cache=True, nogil=True)
def place(
    z: np.ndarray,
    y: np.ndarray,
    starts: np.ndarray,
    cps: np.ndarray,
    n_c: int,
    w_rad_s: float,
    t_first_s: float,
    phase0_rad: float,
    dt_s: float,
) -> None:
    """Add the CP-OFDM symbols y [S, n] (IFFT outputs) to z from sample n_c on, times the
    LOS phasor e^{j(w t + φ0)} at receive times t = t_first + m dt.

    Symbol i occupies samples starts[i] .. starts[i] + n + cps[i] - 1 (relative to n_c),
    read cyclically from y[i] (0..n-1, then the cyclic extension 0..cps[i]-1: the CP is
    folded into the subcarrier phase ramp); samples past the end of z are dropped. The
    phasor is exact at each symbol start times a per-sample factor within the symbol.

    Parameters
    ----------
    z : numpy.ndarray of complex64
        The burst [T], added to in place.
    y : numpy.ndarray of complex64
        IFFT output of every symbol: [S, n].
    starts : numpy.ndarray of int64
        Symbol starts relative to n_c, increasing [samples]: [S].
    cps : numpy.ndarray of int64
        CP lengths [samples]: [S].
    n_c : int
        Sample of z where the first symbol starts (the link's integer delay) [samples].
    w_rad_s : float
        LOS Doppler angular frequency w = 2π f [rad/s].
    t_first_s : float
        Receive time of sample n_c [s].
    phase0_rad : float
        LOS phase φ0 [rad].
    dt_s : float
        Sample period [s].
    """
    n_s, n = y.shape
    total = z.size
    max_len = n + int(cps.max())
    fine = np.empty(max_len, dtype=np.complex64)
    for j in range(max_len):
        fine[j] = np.exp(1j * w_rad_s * j * dt_s)
    for i in range(n_s):
        m0 = starts[i]
        if n_c + m0 >= total:
            break
        length = min(n + cps[i], total - n_c - m0)
        coarse = np.complex64(np.exp(1j * (w_rad_s * (t_first_s + m0 * dt_s) + phase0_rad)))
        base = n_c + m0
        top = min(length, n)
        for j in range(top):
            z[base + j] += y[i, j] * (coarse * fine[j])
        for j in range(n, length):
            z[base + j] += y[i, j - n] * (coarse * fine[j])


@njit(cache=True, nogil=True)
def mix_taps(
    z: np.ndarray,
    delayed: np.ndarray,
    coarse: np.ndarray,
    step: int,
    sym_of: np.ndarray,
    per_symbol: bool,
    mult: np.ndarray,
    los: np.ndarray,
    los_amp: float,
) -> None:
    """z[m] += los_amp · los[m] · delayed[0, m] + mult[m] · Σ_l g_l(m) · delayed[1 + l, m], in
    place (the exact reference's time-varying channel, :mod:`railradio.nr.synthesis.reference`).

    g_l(m) is ``coarse[sym_of[m], l]`` when ``per_symbol`` (gains held per symbol), else the
    linear interpolation of ``coarse`` [C, L], given at samples 0, step, 2·step, …. NumPy
    form (per sample): ``g = interp(m, step·arange(C), coarse)``;
    ``z += los_amp·los·delayed[0] + mult·(g·delayed[1:].T).sum(1)``. ``delayed`` [1 + L, T].

    Parameters
    ----------
    z : numpy.ndarray of complex
        Received samples [T], added to in place.
    delayed : numpy.ndarray of complex64
        The burst delayed by the LOS tap (row 0) and by each Rayleigh tap: [1 + L, T].
    coarse : numpy.ndarray of complex
        Tap gains [√linear]: [S, L] per symbol, or [C, L] at samples 0, step, 2·step, ….
    step : int
        Samples between rows of ``coarse`` (interpolated case) [samples].
    sym_of : numpy.ndarray of int64
        Symbol of each sample (read only when ``per_symbol``): [T].
    per_symbol : bool
        Hold the gains per symbol instead of interpolating.
    mult : numpy.ndarray of complex
        Phasor multiplying the Rayleigh taps' sum: [T].
    los : numpy.ndarray of complex
        LOS phasor: [T].
    los_amp : float
        LOS tap amplitude √P_LOS [√linear].
    """
    n_t = z.size
    n_l = coarse.shape[1]
    for m in range(n_t):
        acc = 0j
        if per_symbol:
            s = sym_of[m]
            for l in range(n_l):
                acc += coarse[s, l] * delayed[1 + l, m]
        else:
            c = m // step
            w = (m - c * step) / step
            for l in range(n_l):
                g = coarse[c, l] + w * (coarse[c + 1, l] - coarse[c, l])
                acc += g * delayed[1 + l, m]
        z[m] += los_amp * los[m] * delayed[0, m] + mult[m] * acc


@njit(cache=True, nogil=True)
def add_spill(
    z: np.ndarray,
    at: np.ndarray,
    col_of: np.ndarray,
    b: np.ndarray,
    gains: np.ndarray,
    starts: np.ndarray,
    n_c: int,
    w_rad_s: float,
    t_first_s: float,
    phase0_rad: float,
    dt_s: float,
) -> None:
    """z[n_c + starts[s] + j] += LOS(m) · Σ_{l: j < b[l]} gains[s, l] · at[s, col_of[l, j]], in
    place: the delayed taps' spill across symbol boundaries (:class:`railradio.nr.synthesis.synthesizer.
    Synthesizer`), from ``at`` [S, Q], the boundary difference's waveform at each tap's delayed
    sample positions, and the receive symbol's held tap gains; LOS(m) is :func:`place`'s
    phasor (exact at each symbol start times a per-sample factor). Samples past the end of z
    are dropped. NumPy form: ``for s, l, j: z[n_c + starts[s] + j] += los[m] * gains[s, l] *
    at[s, col_of[l, j]]`` over j < b[l].

    Parameters
    ----------
    z : numpy.ndarray of complex64
        The burst [T], added to in place.
    at : numpy.ndarray of complex64
        Boundary differences' waveform at the taps' delayed sample positions: [S, Q].
    col_of : numpy.ndarray of int64
        Column of ``at`` for tap l and sample j: [L, max(b)] or wider.
    b : numpy.ndarray of int64
        Spill length of each tap [samples]: [L].
    gains : numpy.ndarray of complex64
        Held tap gains per receive symbol [√linear]: [S, L].
    starts : numpy.ndarray of int64
        Symbol starts relative to n_c [samples]: [S].
    n_c : int
        Sample of z where the first symbol starts [samples].
    w_rad_s : float
        LOS Doppler angular frequency [rad/s].
    t_first_s : float
        Receive time of sample n_c [s].
    phase0_rad : float
        LOS phase φ0 [rad].
    dt_s : float
        Sample period [s].
    """
    n_s = at.shape[0]
    n_l = b.size
    total = z.size
    j_max = 0
    for l in range(n_l):
        j_max = max(j_max, b[l])
    fine = np.empty(j_max, dtype=np.complex64)
    for j in range(j_max):
        fine[j] = np.exp(1j * w_rad_s * j * dt_s)
    acc = np.empty(j_max, dtype=np.complex64)
    for s in range(n_s):
        base = n_c + starts[s]
        if base >= total:
            break
        for j in range(j_max):
            acc[j] = 0
        for l in range(n_l):
            g = gains[s, l]
            for j in range(b[l]):
                acc[j] += g * at[s, col_of[l, j]]
        coarse = np.complex64(np.exp(1j * (w_rad_s * (t_first_s + starts[s] * dt_s) + phase0_rad)))
        for j in range(min(j_max, total - base)):
            z[base + j] += acc[j] * (coarse * fine[j])


@njit(cache=True, nogil=True)
def place_symbols(z: np.ndarray, y: np.ndarray, first: np.ndarray) -> None:
    """z[first[s] + j] = y[s, j mod n] for first[s] <= first[s] + j < first[s + 1] (the last
    symbol: n + its CP, given as ``first[S]``), samples outside z dropped: rectangular symbol
    extents read cyclically from each symbol's IFFT output (the exact reference's placement,
    :mod:`railradio.nr.synthesis.reference`). NumPy form: for each s, ``z[a:b] = y[s, arange(b - a) % n]``.

    Parameters
    ----------
    z : numpy.ndarray of complex64
        Output samples [T], written in place (samples outside every extent untouched).
    y : numpy.ndarray of complex64
        IFFT output of every symbol: [S, n].
    first : numpy.ndarray of int64
        First sample of each symbol's extent, then the end of the last [samples]: [S + 1].
    """
    n_s, n = y.shape
    total = z.size
    for s in range(n_s):
        a = first[s]
        b = min(first[s + 1], total)
        for m in range(max(a, 0), b):
            z[m] = y[s, (m - a) % n]


@njit(cache=True, nogil=True)
def scatter_rows(acc: np.ndarray, base: np.ndarray, lo: int, local: np.ndarray) -> None:
    """acc[(base[s] + lo + w) mod M, :] += local[s, w, :] (M = len(acc), the front end's
    period) for every symbol s and offset w, in
    place: one link's edge values added around each symbol start on the F_s/D_fe grid, as
    :meth:`railradio.nr.synthesis.band_edges.BandEdges._scatter` adds them (each element of ``acc``
    receives at most one value per symbol, in the same complex128 arithmetic).

    Parameters
    ----------
    acc : numpy.ndarray of complex128
        The edges' accumulator [M, J], added to in place.
    base : numpy.ndarray of int64
        Each symbol's start on the grid, [S].
    lo : int
        The link's first offset from the symbol starts.
    local : numpy.ndarray of complex64
        Values [S, W, J].
    """
    m = acc.shape[0]
    n_s, width, n_j = local.shape
    for s in range(n_s):
        for w in range(width):
            row = (base[s] + lo + w) % m
            for j in range(n_j):
                acc[row, j] += np.complex128(local[s, w, j])
