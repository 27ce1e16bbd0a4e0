"""Compiled inner loops of the burst engine's receiver (numba, no ``fastmath``: the compiler
may not reorder a sum or fuse a multiply-add, so a generic x86-64 build and the host's give
the same numbers).

Each kernel fuses passes that :class:`railradio.nr.correlator.Correlator` makes over
separate NumPy or numba arrays; ``tests/nr/test_engine.py`` holds them to that formulation.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def load_products(zf: np.ndarray, spec: np.ndarray, out: np.ndarray) -> None:
    """out[b, f] = zf[b, f] · spec[f]: one cell's cross-spectra over every block (complex64,
    written into a reused buffer) — what :func:`railradio.nr.kernels.cross_spectra` writes
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
    :func:`railradio.nr.kernels.magnitude_stats` computes them (float32 magnitudes, float64
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
    θ_h = 2π f δ_h/N, give c(k0 ± δ_h) = (A ± jS)/N. Sums in complex128 in bin order.

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
    cs : numpy.ndarray of float64
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
            ar = 0.0
            ai = 0.0
            sr = 0.0
            si = 0.0
            q = 0
            for f in range(n):
                p = zf[b, f] * spec[cell, f]
                pr = np.float64(p.real)
                pim = np.float64(p.imag)
                rr = np.float64(roots[q].real)
                ri = np.float64(roots[q].imag)
                vr = pr * rr - pim * ri
                vi = pr * ri + pim * rr
                co = cs[h, f]
                si_f = cs[n_h + h, f]
                ar += vr * co
                ai += vi * co
                sr += vr * si_f
                si += vi * si_f
                q += step
                if q >= n:
                    q -= n
            # c(k0 + δ) = A + jS, c(k0 - δ) = A - jS with A = ar + j ai, S = sr + j si
            out[i, n_h + h] = np.sqrt((ar - si) ** 2 + (ai + sr) ** 2) / n
            out[i, n_h - 1 - h] = np.sqrt((ar + si) ** 2 + (ai - sr) ** 2) / n
    return out


@njit(cache=True, nogil=True)
def ca_cfar_peak(r: np.ndarray, window: int, guard: int) -> tuple:
    """The lag maximizing r/floor per row and r and the floor there, where the floor is the mean
    of r over ``window`` lags on each side beyond ``guard`` (fewer at the row's ends): what
    :func:`railradio.nr.kernels.local_mean_argmax` returns, in one pass over the prefix sums
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
def scatter_rows(acc: np.ndarray, base: np.ndarray, lo: int, local: np.ndarray) -> None:
    """acc[(base[s] + lo + w) mod M, :] += local[s, w, :] for every symbol s and offset w, in
    place: one link's edge values added around each symbol start on the F_s/D_fe grid, as
    :meth:`railradio.nr.band_edges.BandEdges._scatter` adds them (each element of ``acc``
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
