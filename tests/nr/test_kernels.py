"""The compiled kernels (railradio.nr.synthesis.kernels) against the NumPy formulations they replace."""

from __future__ import annotations

import numpy as np
import pytest

from railradio.nr.channel.tdl import sos_eval, sos_params
from railradio.nr.receiver import kernels as receiver_kernels
from railradio.nr.synthesis import kernels


def test_sos_taps_match_direct_evaluation():
    rng = np.random.default_rng(12)
    alpha, phi = sos_params(rng, 3, 16)
    powers = np.array([0.5, 0.3, 0.2])
    # symbol-centre times of a burst far into the track: two distinct steps (normal and
    # long CP) whose float differences carry ~1e-13 s rounding
    steps = np.where(np.arange(500) % 112 == 0, 1224, 1096) / 245.76e6
    t = 371.3 + np.cumsum(steps)
    a = sos_eval(powers, 13e3, t, alpha, phi)
    b = kernels.sos_taps(np.sqrt(powers / 16), 13e3 * np.cos(alpha), phi, t)
    np.testing.assert_allclose(b, a, atol=2e-5)  # sos_eval works in float32 phases


def test_fill_grid_matches_numpy_form():
    rng = np.random.default_rng(3)
    n_s, n, n_p = 40, 16, 7
    c64 = np.complex64

    def crandn(*shape):
        return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(c64)

    pool, h, ramp = crandn(n_p, n), crandn(n_s, n), crandn(n)
    idx = rng.integers(0, n_p, n_s)
    mask = rng.random((n_s, n)) < 0.3
    mask[5:9] = False  # rows without overlay
    mask[20:23] = True  # rows overlaid over the whole band
    vals = np.where(mask, crandn(n_s, n), 0).astype(c64)
    rows = np.flatnonzero(mask.any(axis=1))
    ov_row = np.full(n_s, -1, dtype=np.int64)
    ov_row[rows] = np.arange(rows.size)
    ov = (ov_row, mask[rows].all(axis=1), np.ascontiguousarray(mask[rows]), np.ascontiguousarray(vals[rows]))
    g = rng.random(n_s).astype(np.float32)
    long_of = np.full(n_s, -1)
    long_of[[0, 17]] = [0, 1]
    long_ramp = crandn(2, n)
    for has_h in (True, False):
        grid = pool[idx]
        grid[mask] = vals[mask]
        want = grid * (h if has_h else 1) * ramp[None, :] * g[:, None]
        want[[0, 17]] *= long_ramp
        x = np.empty((n_s, n), dtype=c64)
        kernels.fill_grid(x, pool, idx, *ov, h, has_h, ramp, g, long_of, long_ramp)
        np.testing.assert_allclose(x, want, rtol=1e-5, atol=1e-5)


def test_place_matches_numpy_form():
    rng = np.random.default_rng(4)
    n = 16
    cps = np.array([3, 1, 1, 1, 3, 1], dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(n + cps)[:-1]]).astype(np.int64)
    total = int(starts[-1] + n + cps[-1])
    y = (rng.standard_normal((cps.size, n)) + 1j * rng.standard_normal((cps.size, n))).astype(np.complex64)
    # the NumPy form: gather index of each output sample, then one phasor per sample
    row = np.repeat(np.arange(cps.size), n + cps)
    m = np.arange(total) - np.repeat(starts, n + cps)
    flat = row * n + (m % n)
    w, t_first, phase0, dt = 2 * np.pi * 9.7e3, 12.3, 0.4, 1 / 30.72e6
    for n_c in (0, 5, total - 3, total + 2):
        want = np.zeros(total, dtype=complex)
        if n_c < total:
            k = np.arange(total - n_c)
            want[n_c:] = y.reshape(-1)[flat[: total - n_c]] * np.exp(1j * (w * (t_first + k * dt) + phase0))
        z = np.zeros(total, dtype=np.complex64)
        kernels.place(z, y, starts, cps, n_c, w, t_first, phase0, dt)
        np.testing.assert_allclose(z, want, atol=1e-5)


def test_add_spill_matches_numpy_form():
    rng = np.random.default_rng(6)
    starts = np.array([0, 19, 36, 53], dtype=np.int64)
    b = np.array([0, 2, 5, 1], dtype=np.int64)
    col_of = np.zeros((4, 5), dtype=np.int64)
    q = 0
    for l in range(4):
        for j in range(b[l]):
            col_of[l, j] = q
            q += 1
    at = (rng.standard_normal((4, q)) + 1j * rng.standard_normal((4, q))).astype(np.complex64)
    gains = (rng.standard_normal((4, 4)) + 1j * rng.standard_normal((4, 4))).astype(np.complex64)
    w, t_first, phase0, dt = 2 * np.pi * 9.7e3, 12.3, 0.4, 1 / 30.72e6
    for n_c, total in ((0, 80), (7, 80), (7, 62)):
        want = np.zeros(total, dtype=complex)
        for s in range(4):
            for l in range(4):
                for j in range(b[l]):
                    m = n_c + starts[s] + j
                    if m < total:
                        want[m] += (
                            gains[s, l] * at[s, col_of[l, j]] * np.exp(1j * (w * (t_first + (m - n_c) * dt) + phase0))
                        )
        z = np.zeros(total, dtype=np.complex64)
        kernels.add_spill(z, at, col_of, b, gains, starts, n_c, w, t_first, phase0, dt)
        np.testing.assert_allclose(z, want, atol=1e-5)


def test_magnitude_stats_match_numpy():
    rng = np.random.default_rng(5)
    c = (rng.standard_normal((9, 50)) + 1j * rng.standard_normal((9, 50))).astype(np.complex64)
    r, mu, sigma, eta, arg = receiver_kernels.magnitude_stats(c, 40)
    a = np.abs(c[:, :40])
    np.testing.assert_allclose(r, a, rtol=1e-6)
    np.testing.assert_allclose(mu, a.mean(axis=1), rtol=1e-6)
    np.testing.assert_allclose(sigma, a.std(axis=1), rtol=1e-5)
    np.testing.assert_allclose(eta, a.max(axis=1), rtol=1e-6)
    np.testing.assert_array_equal(arg, a.argmax(axis=1))


@pytest.mark.parametrize("window,guard,k", [(5, 2, 150), (64, 4, 150), (64, 4, 822), (64, 4, 30)])
def test_local_mean_argmax_matches_a_direct_loop(window, guard, k):
    rng = np.random.default_rng(13)
    r = rng.random((4, k)).astype(np.float32)
    k_best, eta, floor_at = receiver_kernels.local_mean_argmax(r, window, guard)
    k = r.shape[1]
    floor = np.empty_like(r, dtype=float)
    for j in range(k):
        idx = [i for i in range(j - guard - window, j - guard) if 0 <= i < k] + [
            i for i in range(j + guard + 1, j + guard + 1 + window) if 0 <= i < k
        ]
        floor[:, j] = r[:, idx].mean(axis=1)
    want = (r / floor).argmax(axis=1)
    np.testing.assert_array_equal(k_best, want)
    np.testing.assert_allclose(eta, r[np.arange(4), want])
    np.testing.assert_allclose(floor_at, floor[np.arange(4), want], rtol=1e-6)


def test_at_offsets_is_the_band_limited_interpolant():
    rng = np.random.default_rng(6)
    n, d = 64, 4
    p = (rng.standard_normal((3, n)) + 1j * rng.standard_normal((3, n))).astype(np.complex64)
    freqs = np.fft.fftfreq(n, 1.0 / n)
    offsets = np.arange(-d, d + 1) / d
    k0 = np.array([0, 17, 63])
    rows = np.array([2, 0, 1])  # rows of p, in any order
    theta = 2 * np.pi * np.outer(offsets[d:], freqs) / n  # the non-negative offsets
    cs_t = np.concatenate([np.cos(theta), np.sin(theta)]).T.astype(np.float32)
    got = receiver_kernels.at_offsets(
        p, k0, np.exp(2j * np.pi * np.arange(n) / n).astype(np.complex64), np.ascontiguousarray(cs_t), rows
    )
    lam = k0[:, None] + offsets[None, :]  # [3, J]
    want = np.abs(np.einsum("rf,rjf->rj", p[rows], np.exp(2j * np.pi * lam[:, :, None] * freqs / n))) / n
    np.testing.assert_allclose(got, want, rtol=1e-4)
    # at integer lags it equals the inverse FFT
    np.testing.assert_allclose(got[:, d], np.abs(np.fft.ifft(p[rows], axis=1))[np.arange(3), k0], rtol=1e-4)


def test_cross_spectra_is_the_broadcast_product():
    rng = np.random.default_rng(7)
    zf = (rng.standard_normal((5, 16)) + 1j * rng.standard_normal((5, 16))).astype(np.complex64)
    bs = (rng.standard_normal((3, 16)) + 1j * rng.standard_normal((3, 16))).astype(np.complex64)
    out = np.empty((3, 5, 16), dtype=np.complex64)
    receiver_kernels.cross_spectra(zf, bs, out)
    np.testing.assert_allclose(out, zf[None, :, :] * bs[:, None, :], rtol=1e-6)


def test_ula_gain_closed_form_equals_the_element_sum():
    """The Dirichlet-kernel array factor equals |Σ_n e^{jπnu}|²/N summed element by element,
    including the endfire/broadside points where both sines of the closed form vanish."""
    from railradio.nr.channel.antenna import ARRAY_NULL_FLOOR, ula_gain

    rng = np.random.default_rng(11)
    phi = np.concatenate([rng.uniform(-np.pi, np.pi, 20000), [np.pi / 2, -np.pi / 2, 0.0, 1e-9]])
    steer = np.concatenate([rng.uniform(-np.pi, np.pi, 20000), [-np.pi / 2, np.pi / 2, 0.0, 0.0]])
    for n in (1, 8, 32):
        u = np.sin(phi)[:, None] - np.sin(steer)[:, None]
        ref = np.maximum(np.abs(np.exp(1j * np.pi * u * np.arange(n)).sum(axis=1)) ** 2 / n, ARRAY_NULL_FLOOR)
        np.testing.assert_allclose(ula_gain(phi, steer, n), ref, rtol=1e-11)
    assert ula_gain(0.3, 0.3, 8) == pytest.approx(8.0)
