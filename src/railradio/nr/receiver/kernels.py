"""Compiled inner loops of the burst engine's receiver (numba, no ``fastmath``: the compiler
may not reorder a sum or fuse a multiply-add, so a generic x86-64 build and the host's give
the same numbers).

Each kernel fuses passes that :class:`railradio.nr.receiver.correlator.Correlator` makes over
separate NumPy or numba arrays; ``tests/nr/test_engine.py`` holds them to that formulation.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def load_products(zf: np.ndarray, spec: np.ndarray, out: np.ndarray) -> None:
    """out[b, f] = zf[b, f] · spec[f]: one cell's cross-spectra over every block (complex64,
    written into a reused buffer) — what :func:`railradio.nr.receiver.kernels.cross_spectra` writes
    for one candidate.

    Parameters
    ----------
    zf : numpy.ndarray of complex64
        Window spectra of the received burst, [B, N].
    spec : numpy.ndarray of complex64
        A conjugate reference spectrum, [N].
    out : numpy.ndarray of complex64
        Output, overwritten, [B, N].
    """
    n_b, n = zf.shape
    for b in range(n_b):
        for f in range(n):
            out[b, f] = zf[b, f] * spec[f]


@njit(cache=True, nogil=True)
def row_stats(c: np.ndarray, other: np.ndarray, add: bool, k: int, r: np.ndarray, edge: np.ndarray, stats: np.ndarray):
    """|c + other| (``add``) or |c| over the leading ``k`` lags of each row, with the per-row
    mean, standard deviation (ddof 0), maximum and its lag in one pass, as
    :func:`railradio.nr.receiver.kernels.magnitude_stats` computes them (float32 magnitudes, float64
    sums); and the magnitudes just outside the window, at lag -1 (circular: N - 1) and lag k,
    which the peak refinement reads at the window's ends.

    Parameters
    ----------
    c, other : numpy.ndarray of complex64
        Correlation rows [R, N] (lags along the last axis); ``other`` is read only when ``add``.
    add : bool
        Use c + other (a template made of two parts) instead of c.
    k : int
        Lags of the window, k < N.
    r : numpy.ndarray of float32
        Output magnitudes [R, k].
    edge : numpy.ndarray of float32
        Output [R, 2]: the magnitudes at lag -1 and lag k.
    stats : numpy.ndarray of float64
        Output [R, 4]: mean, standard deviation, maximum, lag of the maximum (units of |c|; lag as float).
    """
    n_r, n = c.shape
    for i in range(n_r):
        s1 = 0.0
        s2 = 0.0
        best = -1.0
        bi = 0
        for j in range(k):
            v = c[i, j] + other[i, j] if add else c[i, j]
            a = np.sqrt(v.real * v.real + v.imag * v.imag)
            r[i, j] = a
            a64 = np.float64(np.float32(a))
            s1 += a64
            s2 += a64 * a64
            if a64 > best:
                best = a64
                bi = j
        for e in range(2):
            j = n - 1 if e == 0 else k
            v = c[i, j] + other[i, j] if add else c[i, j]
            edge[i, e] = np.sqrt(v.real * v.real + v.imag * v.imag)
        m = s1 / k
        stats[i, 0] = m
        stats[i, 1] = np.sqrt(max(s2 / k - m * m, 0.0))
        stats[i, 2] = best
        stats[i, 3] = bi


@njit(cache=True, nogil=True)
def between_lags(
    zf: np.ndarray,
    spec: np.ndarray,
    blocks: np.ndarray,
    cells: np.ndarray,
    k0: np.ndarray,
    roots: np.ndarray,
    cs: np.ndarray,
) -> np.ndarray:
    """Band-limited |c(k0 ± δ_h)| at the offsets between the lag grid's samples, straight from
    the window spectra: c(λ) = (1/N) Σ_f zf[b, f] spec[cell, f] e^{j2π f λ/N}, with f the
    signed frequency of each bin for the fractional part (as the correlator's
    ``offset_cs_t``) and the root table for the integer part k0.

    With q[f] = zf[b, f] spec[cell, f] e^{j2π f k0/N}, A = Σ q cos θ_h and S = Σ q sin θ_h,
    θ_h = 2π f δ_h/N, give c(k0 ± δ_h) = (A ± jS)/N. Products and sums in float32 in bin
    order, as the correlator's float32 product with ``offset_cs_t`` (its refinement) rounds;
    the magnitudes in float64.

    Parameters
    ----------
    zf : numpy.ndarray of complex64
        Window spectra [B, N].
    spec : numpy.ndarray of complex64
        Conjugate reference spectra [n_spec, N].
    blocks, cells : numpy.ndarray of int64
        Per evaluation, the block (row of ``zf``) and the spectrum (row of ``spec``), [R].
    k0 : numpy.ndarray of int64
        Per evaluation, the lag on the correlation grid, [R].
    roots : numpy.ndarray of complex64
        e^{j2π q/N}, q = 0 … N - 1, [N].
    cs : numpy.ndarray of float32
        cos θ_h over sin θ_h per positive offset δ_h, [2H, N].

    Returns
    -------
    numpy.ndarray of float64
        [R, 2H]: |c(k0 - δ_h)| for h = H-1 … 0, then |c(k0 + δ_h)| for h = 0 … H-1 (offsets
        ascending).
    """
    n = zf.shape[1]
    n_h = cs.shape[0] // 2
    n_r = blocks.shape[0]
    out = np.empty((n_r, 2 * n_h))
    for i in range(n_r):
        b = blocks[i]
        cell = cells[i]
        step = k0[i] % n
        for h in range(n_h):
            ar = np.float32(0.0)
            ai = np.float32(0.0)
            sr = np.float32(0.0)
            si = np.float32(0.0)
            q = 0
            for f in range(n):
                v = zf[b, f] * spec[cell, f] * roots[q]
                co = cs[h, f]
                si_f = cs[n_h + h, f]
                ar += v.real * co
                ai += v.imag * co
                sr += v.real * si_f
                si += v.imag * si_f
                q += step
                if q >= n:
                    q -= n
            # c(k0 + δ) = A + jS, c(k0 - δ) = A - jS with A = ar + j ai, S = sr + j si
            a_r, a_i, s_r, s_i = np.float64(ar), np.float64(ai), np.float64(sr), np.float64(si)
            out[i, n_h + h] = np.sqrt((a_r - s_i) ** 2 + (a_i + s_r) ** 2) / n
            out[i, n_h - 1 - h] = np.sqrt((a_r + s_i) ** 2 + (a_i - s_r) ** 2) / n
    return out


@njit(cache=True, nogil=True)
def ca_cfar_peak(r: np.ndarray, window: int, guard: int) -> tuple:
    """The lag maximizing r/floor per row and r and the floor there, where the floor is the mean
    of r over ``window`` lags on each side beyond ``guard`` (fewer at the row's ends): what
    :func:`railradio.nr.receiver.kernels.local_mean_argmax` returns, in one pass over the prefix sums
    (the floor is not stored).

    Parameters
    ----------
    r : numpy.ndarray of float32
        Correlation magnitudes [R, K].
    window, guard : int
        Averaging and guard lags on each side.

    Returns
    -------
    tuple of numpy.ndarray
        (k_best [R] int64, r at k_best [R] float64, the floor at k_best [R] float64).
    """
    n_r, k = r.shape
    c = np.empty(k + 1)
    k_best = np.empty(n_r, dtype=np.int64)
    eta = np.empty(n_r)
    floor_at = np.empty(n_r)
    n_full = 2 * window
    for i in range(n_r):
        c[0] = 0.0
        for j in range(k):
            c[j + 1] = c[j] + r[i, j]
        best = -1.0
        bj = 0
        bf = 0.0
        for j in range(k):
            a0 = j - guard - window
            b1 = j + guard + 1 + window
            if a0 >= 0 and b1 <= k:
                fl = ((c[j - guard] - c[a0]) + (c[b1] - c[j + guard + 1])) / n_full
            else:
                lo0 = min(max(a0, 0), k)
                lo1 = min(max(j - guard, 0), k)
                hi0 = min(max(j + guard + 1, 0), k)
                hi1 = min(max(b1, 0), k)
                cnt = (lo1 - lo0) + (hi1 - hi0)
                fl = ((c[lo1] - c[lo0]) + (c[hi1] - c[hi0])) / max(cnt, 1)
            ratio = r[i, j] / max(fl, 1e-30)
            if ratio > best:
                best = ratio
                bj = j
                bf = fl
        k_best[i] = bj
        eta[i] = r[i, bj]
        floor_at[i] = bf
    return k_best, eta, floor_at


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
    :class:`railradio.nr.receiver.correlator.Correlator` defines it) and the lag maximizing r/floor.

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
