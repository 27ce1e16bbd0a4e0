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
    ``amp_l[None, :] * railradio.nr.channel.sos_eval(...)`` sums to ~1e-13.

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
def magnitude_stats(c: np.ndarray, k: int) -> tuple:
    """|c[..., :k]| and its per-row mean, standard deviation (ddof 0), max and argmax, in
    one pass over rows of c [R, N] (complex64): (r [R, k] float32, mu, sigma, eta, k_max).

    Parameters
    ----------
    c : numpy.ndarray of complex64
        Correlation rows [R, N] (lags along the last axis).
    k : int
        Number of leading lags used; k <= N.

    Returns
    -------
    tuple of numpy.ndarray
        r [R, k] float32; mu, sigma, eta [R] float64 (units of |c|); k_max [R] int64 (lag index).
    """
    n_r = c.shape[0]
    r = np.empty((n_r, k), dtype=np.float32)
    mu = np.empty(n_r)
    sigma = np.empty(n_r)
    eta = np.empty(n_r)
    arg = np.empty(n_r, dtype=np.int64)
    for i in range(n_r):
        s1 = 0.0
        s2 = 0.0
        best = -1.0
        bi = 0
        for j in range(k):
            v = c[i, j]
            a = np.sqrt(v.real * v.real + v.imag * v.imag)
            r[i, j] = a
            a64 = np.float64(np.float32(a))
            s1 += a64
            s2 += a64 * a64
            if a64 > best:
                best = a64
                bi = j
        m = s1 / k
        mu[i] = m
        sigma[i] = np.sqrt(max(s2 / k - m * m, 0.0))
        eta[i] = best
        arg[i] = bi
    return r, mu, sigma, eta, arg


@njit(cache=True, nogil=True, inline="always")
def _clamped_floor(c: np.ndarray, j: int, k: int, window: int, guard: int) -> float:
    """Mean of r over the window lags on each side of j beyond ``guard``, from the prefix
    sums c, with the windows cut at 0 and k."""
    a0 = min(max(j - guard - window, 0), k)
    a1 = min(max(j - guard, 0), k)
    b0 = min(max(j + guard + 1, 0), k)
    b1 = min(max(j + guard + 1 + window, 0), k)
    cnt = (a1 - a0) + (b1 - b0)
    return ((c[a1] - c[a0]) + (c[b1] - c[b0])) / max(cnt, 1)


@njit(cache=True, nogil=True)
def local_mean_argmax(r: np.ndarray, window: int, guard: int) -> tuple:
    """Cell-averaging CFAR per row of r [R, K]: the floor at each lag (mean of r over
    ``window`` lags on each side beyond ``guard``, fewer at the ends, as the CA-CFAR detector of
    :class:`railradio.nr.correlator.Correlator` defines it) and the lag maximizing r/floor.

    Parameters
    ----------
    r : numpy.ndarray
        Correlation magnitudes [R, K] (float32 from the correlator).
    window : int
        Averaging lags on each side [lags].
    guard : int
        Guard lags on each side of the tested lag [lags].

    Returns
    -------
    tuple of numpy.ndarray
        (k_best [R] int64, eta = r at k_best [R], floor at k_best [R]); eta, floor float64 in units of r.
    """
    n_r, k = r.shape
    c = np.empty(k + 1)
    fl = np.empty(k)
    ratio = np.empty(k)
    k_best = np.empty(n_r, dtype=np.int64)
    eta = np.empty(n_r)
    floor_at = np.empty(n_r)
    # lags whose windows are whole on both sides: no clamping (a loop the compiler vectorizes)
    j_lo = guard + window
    j_hi = k - guard - window  # exclusive
    n_full = 2 * window
    for i in range(n_r):
        c[0] = 0.0
        for j in range(k):
            c[j + 1] = c[j] + r[i, j]
        for j in range(0, min(j_lo, k)):  # clamped windows at both edges
            fl[j] = _clamped_floor(c, j, k, window, guard)
        for j in range(max(j_hi, j_lo), k):
            fl[j] = _clamped_floor(c, j, k, window, guard)
        for j in range(j_lo, j_hi):
            fl[j] = ((c[j - guard] - c[j - guard - window]) + (c[j + guard + 1 + window] - c[j + guard + 1])) / n_full
        for j in range(k):
            ratio[j] = r[i, j] / max(fl[j], 1e-30)
        best = -1.0
        bj = 0
        for j in range(k):
            if ratio[j] > best:
                best = ratio[j]
                bj = j
        k_best[i] = bj
        eta[i] = r[i, bj]
        floor_at[i] = fl[bj]
    return k_best, eta, floor_at


@njit(cache=True, nogil=True)
def shifted_parts(p: np.ndarray, k0: np.ndarray, roots: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """q_i[f] = p[rows[i], f] · e^{j2π f k0[i]/N} split into parts, [2R, N] float32: rows
    0 … R-1 the real parts, R … 2R-1 the imaginary parts. ``roots[q] = e^{j2π q/N}``; the
    index advances by k0 mod N per bin (no modulo per bin).

    Parameters
    ----------
    p : numpy.ndarray of complex64
        Cross-spectra [M, N].
    k0 : numpy.ndarray of int64
        Lag of each row [samples at the correlation rate]: [R].
    roots : numpy.ndarray of complex64
        e^{j2π q/N} for q = 0 .. N - 1: [N].
    rows : numpy.ndarray of int64
        Rows of ``p`` to use: [R].

    Returns
    -------
    numpy.ndarray of float32
        Real parts (rows 0 .. R-1) over imaginary parts: [2R, N].
    """
    n = p.shape[1]
    n_r = rows.shape[0]
    out = np.empty((2 * n_r, n), dtype=np.float32)
    for i in range(n_r):
        row = rows[i]
        step = k0[i] % n
        q = 0
        for f in range(n):
            v = p[row, f] * roots[q]
            out[i, f] = v.real
            out[n_r + i, f] = v.imag
            q += step
            if q >= n:
                q -= n
    return out


def at_offsets(p: np.ndarray, k0: np.ndarray, roots: np.ndarray, cs_t: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Band-limited |c(k0 + δ)| = |(1/N) Σ_f p[f] e^{j2π f (k0 + δ)/N}| at the symmetric
    offsets δ = -δ_{H-1} … -δ_1, 0, δ_1 … δ_{H-1} for the rows ``rows`` [R] of the
    cross-spectra p [M, N] (row i of the result: p[rows[i]], k0[i]).

    ``cs_t`` [N, 2H] holds cos(2π f δ_h/N) in its first H columns and sin(2π f δ_h/N) in
    the others, for the non-negative offsets (δ_0 = 0). With q[f] = p[f] e^{j2π f k0/N},
    A = Σ q cos θ and S = Σ q sin θ give c(k0 ± δ) = (A ± jS)/N. A and S of every row and
    offset are one float32 matrix product [2R, N] × [N, 2H] (BLAS sgemm: its summation
    order is fixed by the kernel, which the jobs pin, ``railradio.workflow.JOB_ENV``, so
    the result does not depend on the CPU). Relative error ~1e-5. Returns [R, 2H - 1].

    Parameters
    ----------
    p : numpy.ndarray of complex64
        Cross-spectra [M, N].
    k0 : numpy.ndarray of int64
        Centre lag of each row [samples at the correlation rate]: [R].
    roots : numpy.ndarray of complex64
        e^{j2π q/N} for q = 0 .. N - 1: [N].
    cs_t : numpy.ndarray of float32
        cos | sin of 2π f δ_h/N for the H offsets δ_h >= 0: [N, 2H].
    rows : numpy.ndarray of int64
        Rows of ``p`` to use: [R].

    Returns
    -------
    numpy.ndarray of float64
        |c(k0 + δ)| (units of |c|), offsets ascending: [R, 2H - 1].
    """
    n = p.shape[1]
    n_h = cs_t.shape[1] // 2
    n_r = rows.shape[0]
    m = (shifted_parts(p, k0, roots, rows) @ cs_t).astype(np.float64)
    a_re, s_re = m[:n_r, :n_h], m[:n_r, n_h:]
    a_im, s_im = m[n_r:, :n_h], m[n_r:, n_h:]
    out = np.empty((n_r, 2 * n_h - 1))
    out[:, n_h - 1 :] = np.sqrt((a_re - s_im) ** 2 + (a_im + s_re) ** 2) / n  # c(k0 + δ) = A + jS
    out[:, n_h - 1 :: -1] = np.sqrt((a_re + s_im) ** 2 + (a_im - s_re) ** 2) / n  # c(k0 - δ) = A - jS
    return out


@njit(cache=True, nogil=True)
def cross_spectra(zf: np.ndarray, bspec: np.ndarray, out: np.ndarray) -> None:
    """out[c, b, :] = zf[b, :] · bspec[c, :]: the per-candidate, per-block cross-spectra
    (complex64, written into a reused buffer).

    Parameters
    ----------
    zf : numpy.ndarray of complex64
        Window spectra of the received burst: [B, N].
    bspec : numpy.ndarray of complex64
        Conjugate reference spectra of the candidates: [C, N].
    out : numpy.ndarray of complex64
        Output, overwritten: [C, B, N].
    """
    n_c, n = bspec.shape
    n_b = zf.shape[0]
    for c in range(n_c):
        for b in range(n_b):
            for f in range(n):
                out[c, b, f] = zf[b, f] * bspec[c, f]


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
    place (the exact reference's time-varying channel, :mod:`railradio.nr.reference`).

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
    place: the delayed taps' spill across symbol boundaries (:class:`railradio.nr.synthesis.
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
    :mod:`railradio.nr.reference`). NumPy form: for each s, ``z[a:b] = y[s, arange(b - a) % n]``.

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
