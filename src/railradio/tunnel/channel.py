"""The slot-to-receiver channel, tabulated once by along-axis offset, and what follows.

A straight tunnel is translation invariant, so the channel from any slot to the receiver
(at its fixed cross-section position) depends only on the offset dx = x_rx - x_slot, and
by the mirror symmetry x -> -x only on |dx|.  :func:`tabulate` evaluates every ray family
on a grid of offsets (a step that divides the slot spacing, so every slot-receiver pair
of a receiver on the grid falls exactly on it) and stores, per offset, the band-limited
channel as complex taps on a fine excess-delay grid (relative to the line-of-sight delay),
their coherent sum being the narrowband gain, plus the local-mean power and the delay
moments.  Gains are relative to the cable power at the slot: the physical model includes
the slot EIRP of the slot-chain calibration (geometry eq. 1); the source's model applies its
own losses (source 2.2-2.4): coupling loss at the slot-receiver distance, free space, tunnel
attenuation, a fixed loss per reflection and a random 0-10 dB multipath loss per
reflected ray.

:func:`received` assembles, for receivers anywhere on the grid, the sum over all slots
with the cable's loss and phase: RSSI coherent and local mean [source 2.4.3], RMS delay
spread [source 2.5.2], per-slot powers and delays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from numba import njit

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.lifting import reflection_product
from railradio.tunnel.rays import Families

PROPAGATIONS = ("physical", "source")


@dataclass(frozen=True)
class SourceModel:
    """The source's simplified propagation model (source 2.3.2-2.4.2)."""

    reflection_loss_db: float = 8.0
    tunnel_att_db_per_m: float = 0.065
    multipath_max_db: float = 10.0


def offset_grid_m(step_m: float, max_offset_m: float, slot_spacing_m: float) -> np.ndarray:
    """Offsets 0, step, ..., max_offset [m]; the step must divide the slot spacing.

    Parameters
    ----------
    step_m : float
        Grid step [m]; positive, and the slot spacing must be an integer multiple of it
        (to 1e-9 relative), so every slot-receiver pair of a receiver on the grid falls on it.
    max_offset_m : float
        Largest offset [m]; positive (rounded to the nearest multiple of ``step_m``).
    slot_spacing_m : float
        Slot spacing of the cable [m].

    Returns
    -------
    numpy.ndarray
        Offsets 0, step, ..., n step with n = round(max_offset_m / step_m) [m].

    Raises
    ------
    ValueError
        When ``step_m`` or ``max_offset_m`` is not positive, or ``step_m`` does not divide
        ``slot_spacing_m``.
    """
    if not step_m > 0 or not max_offset_m > 0:
        raise ValueError("step_m and max_offset_m must be positive")
    ratio = slot_spacing_m / step_m
    if abs(ratio - round(ratio)) > 1e-9:
        raise ValueError(f"step_m={step_m} must divide the slot spacing {slot_spacing_m} m")
    n = int(round(max_offset_m / step_m))
    return np.arange(n + 1) * step_m


def lee_window_m(wavelength_m: float, n_wavelengths: float) -> float:
    """Length of the local-mean window [m]: ``n_wavelengths`` wavelengths (Lee 1985: 40 λ
    with ≥ 36 samples removes the multipath fading and keeps the slower variation)."""
    if not wavelength_m > 0 or not n_wavelengths > 0:
        raise ValueError("wavelength_m and n_wavelengths must be positive")
    return wavelength_m * n_wavelengths


def window_samples(window_m: float, step_m: float) -> int:
    """Odd number of samples ``step_m`` apart spanning ``window_m`` (for :func:`moving_mean`)."""
    return 2 * int(round(0.5 * window_m / step_m)) + 1


def moving_mean(a: np.ndarray, n: int, mirror_start: bool = False) -> np.ndarray:
    """Centred running mean over ``n`` samples (odd) along axis 0.  ``mirror_start``: the
    samples before the first are its mirror images (a function of |dx| sampled from dx = 0);
    otherwise, and at the end, the window holds only the samples that exist."""
    if n < 1 or n % 2 == 0:
        raise ValueError(f"n must be a positive odd number of samples, got {n!r}")
    a = np.asarray(a)
    half = n // 2
    if a.shape[0] == 0 or half == 0:
        return a.astype(float if not np.iscomplexobj(a) else complex)
    if mirror_start:
        pre = a[1 : half + 1][::-1]
        ext = np.concatenate([pre, a], axis=0)
        lead = pre.shape[0]
    else:
        ext, lead = a, 0
    cs = np.concatenate([np.zeros((1, *a.shape[1:])), np.cumsum(ext, axis=0)], axis=0)
    i = np.arange(a.shape[0]) + lead
    lo = np.maximum(i - half, 0)
    hi = np.minimum(i + half + 1, ext.shape[0])
    shape = (-1,) + (1,) * (a.ndim - 1)
    return (cs[hi] - cs[lo]) / (hi - lo).reshape(shape)


def beat_length_m(tunnel: Tunnel, wavelength_m: float) -> float:
    """Beat length 2π / (β11 - β12) of EH11 and EH12 [m] (in the circle the l = 1 group, TE01/TM01/EH21,
    lies between them; its beat with EH11 is longer): across the larger
    side a of the rectangle β_mn ≈ k - (π²/2k)(m²/w² + n²/h²) (Emslie, Lagace & Strong 1975),
    i.e. 8 a² / (3 λ); in the circle of radius a β_1m ≈ k - u_1m²/(2 k a²), u_1m the zeros of
    J_0 (Marcatili & Schmeltzer 1964), i.e. 8 π² a² / (λ (u_12² - u_11²))."""
    if tunnel.shape == "circle":
        return 2.0 * np.pi**2 * tunnel.diameter_m**2 / (wavelength_m * (5.520078110286311**2 - 2.404825557695773**2))
    return 8.0 * max(tunnel.width_m, tunnel.height_m) ** 2 / (3.0 * wavelength_m)


@njit(cache=True, nogil=True)
def _ray(g_grid, f, e, dx, k):
    """Family f's ray (2-D length e) at offset dx: (amplitude, 3-D length).  The reflection
    product is linear in sin b between the rows of ``g_grid`` [f, s] (uniform on [0, 1]),
    which already hold the spreading, caustic phase and scale."""
    n_s = g_grid.shape[1]
    d = math.sqrt(e * e + dx * dx)
    inv = 1.0 / d
    pos = e * inv * (n_s - 1.0)
    i0 = min(int(pos), n_s - 2)
    g = g_grid[f, i0] + (g_grid[f, i0 + 1] - g_grid[f, i0]) * (pos - i0)
    ph = k * d
    return g * inv * complex(math.cos(ph), -math.sin(ph)), d


@njit(cache=True, nogil=True)
def _physical_taps(ell, g_grid, offsets, k, h, c, delay_bin_s, taps, p_inc, block=512):
    """taps[j, b] += every family's ray at offset offsets[j] in its excess-delay bin b (over
    the line of sight); p_inc[j] += the rays' powers.  Blocks of offsets, one family at a
    time (its row of ``g_grid`` stays in cache); every sum runs in family order."""
    n_b = taps.shape[1]
    d_los = np.sqrt(h * h + offsets * offsets)
    for j0 in range(0, offsets.size, block):
        j1 = min(j0 + block, offsets.size)
        for f in range(ell.size):
            for j in range(j0, j1):
                a, d = _ray(g_grid, f, ell[f], offsets[j], k)
                b = min(np.rint((d - d_los[j]) / (c * delay_bin_s)), n_b - 1.0)
                taps[j, int(b)] += a
                p_inc[j] += a.real * a.real + a.imag * a.imag


@njit(cache=True, nogil=True)
def _gain_by_order(ell, n_refl, g_grid, offsets, k, out, block=512):
    """out[n, j] += every family's ray of reflection order n at offset offsets[j] (the
    narrowband field, as :func:`_physical_taps` sums it)."""
    for j0 in range(0, offsets.size, block):
        j1 = min(j0 + block, offsets.size)
        for f in range(ell.size):
            for j in range(j0, j1):
                out[n_refl[f], j] += _ray(g_grid, f, ell[f], offsets[j], k)[0]


def _scaled_product_grid(fam: Families, eps: complex, polarization: str, n_sin_grid: int) -> np.ndarray:
    """The reflection product on ``n_sin_grid`` elevations uniform in sin b, times each
    family's spreading and caustic phase and λ/(4π) (unit EIRP) [f, s]."""
    g = reflection_product(fam, np.linspace(0.0, 1.0, n_sin_grid), eps, polarization)
    return np.ascontiguousarray(g * (fam.spread * np.exp(1j * fam.caustic_phase_rad))[:, None])


def coherent_gain_by_order(
    fam: Families, offsets_m: np.ndarray, wavelength_m: float, eps: complex, polarization: str, n_sin_grid: int = 513
) -> np.ndarray:
    """Narrowband gain of one slot (unit EIRP) at ``offsets_m``, the sum of each reflection
    order apart [order 0..max, offset] (its cumulative sum over orders: the gain truncated
    at each order), with the reflection product interpolated as :func:`tabulate` does."""
    g = _scaled_product_grid(fam, eps, polarization, n_sin_grid) * (wavelength_m / (4.0 * math.pi))
    dx = np.ascontiguousarray(np.abs(np.asarray(offsets_m, dtype=float)).ravel())
    out = np.zeros((int(fam.n_refl.max(initial=0)) + 1, dx.size), dtype=complex)
    _gain_by_order(
        np.ascontiguousarray(fam.ell_m, dtype=float),
        np.ascontiguousarray(fam.n_refl, dtype=np.int64),
        g,
        dx,
        2.0 * math.pi / wavelength_m,
        out,
    )
    return out


def tabulate(
    fam: Families,
    tunnel: Tunnel,
    cable: Cable,
    offsets_m: np.ndarray,
    *,
    eps: complex,
    polarization: str,
    propagation: str = "physical",
    source_model: SourceModel | None = None,
    rng: np.random.Generator | None = None,
    delay_bin_s: float = 10e-9,
    n_delay_bins: int = 64,
    n_sin_grid: int = 513,
    chunk: int = 256,
    local_mean_window_m: float | None = None,
) -> xr.Dataset:
    """Tabulate the slot-to-receiver channel over ``offsets_m`` (see the module docstring).

    The local mean of the physical channel is what a receiver moving along the tunnel
    measures: the power of the coherent ray sum averaged over ``local_mean_window_m`` of
    offsets (required for it; :func:`moving_mean`, mirrored at dx = 0), and the delay
    moments come from the taps' powers averaged over the same window (the local-mean power
    delay profile: rays in one delay bin add coherently, different bins' cross terms
    average out).  The incoherent sum over rays is kept as ``power_incoherent`` for
    comparison; the source's model keeps it as its local mean (source 2.4.3).

    The reflection product of each family is evaluated on ``n_sin_grid`` elevations
    (uniform in sin b, in which the Fresnel coefficients are smooth) and interpolated;
    spreading and phase are exact at every offset.  ``rng`` draws the source model's
    multipath losses (one per reflected ray and offset: every slot-receiver pair its own).

    Parameters
    ----------
    fam : Families
        2-D ray families from the slot to the receiver
        (:func:`railradio.tunnel.rays.image_families` or :func:`~railradio.tunnel.rays.sbr_families`).
    tunnel : Tunnel
        The tunnel of ``fam``: its slot-receiver distance in the cross-section (the
        line-of-sight delay) and slot spacing (the slot EIRP).
    cable : Cable
        The cable: wavelength, slot EIRP (physical), coupling loss (source's model).
    offsets_m : numpy.ndarray
        Along-axis offsets |x_rx - x_slot| [m], a uniform grid from 0 (:func:`offset_grid_m`).
    eps : complex or None
        Relative permittivity of the wall [1] (real part > 1, imaginary part <= 0); None:
        perfectly absorbing walls (only the line of sight).  Physical propagation only.
    polarization : {'paraxial', 'vector'}
        Polarization rule of the reflection product (:mod:`railradio.tunnel.lifting`).
        Physical propagation only.
    propagation : {'physical', 'source'}
        The physical ray channel, or the source's simplified model (source 2.2-2.4).
    source_model : SourceModel or None
        Losses of the source's model (None: the defaults of :class:`SourceModel`).
    rng : numpy.random.Generator or None
        Source of the source model's random multipath losses; required for ``propagation='source'``.
    delay_bin_s : float
        Width of the excess-delay bins of the taps [s]; positive.
    n_delay_bins : int
        Number of excess-delay bins (the last collects every later ray); >= 2.
    n_sin_grid : int
        Elevations (uniform in sin b on [0, 1]) on which the reflection product is evaluated.
    chunk : int
        Offsets evaluated at a time by the source's model (memory only).
    local_mean_window_m : float or None
        Length of the local-mean window [m]; required (> 0) for physical propagation,
        ignored by the source's model.

    Returns
    -------
    xarray.Dataset
        Dims ``offset_m`` (coordinate: the offsets [m]) and ``excess_delay_s`` (bin starts
        over the line of sight [s]).  Variables: ``taps`` [offset_m, excess_delay_s]
        (complex amplitude gain relative to the cable power at the slot [1]),
        ``power_mean`` (local-mean power gain [1]), ``power_incoherent`` (incoherent sum of
        the rays' powers [1]), ``delay_mean_s`` (power-weighted mean delay from the slot
        [s]), ``delay_rms_s`` (RMS delay spread of one slot [s]), ``los_delay_s``
        (line-of-sight delay [s]), each [offset_m].  Attributes: ``engine``,
        ``propagation``, ``polarization``, ``n_families``, ``max_reflections``,
        ``local_mean_window_m`` (0 for the source's model), ``shape``.

    Raises
    ------
    ValueError
        When ``propagation`` is unknown; when ``n_delay_bins`` < 2 or ``delay_bin_s`` <= 0;
        when ``rng`` is None for the source's model; when ``local_mean_window_m`` is missing or
        not positive, or ``polarization`` is unknown, for physical propagation.
    """
    if propagation not in PROPAGATIONS:
        raise ValueError(f"propagation must be one of {PROPAGATIONS}, got {propagation!r}")
    if n_delay_bins < 2 or delay_bin_s <= 0:
        raise ValueError("n_delay_bins must be >= 2 and delay_bin_s > 0")
    lam = cable.wavelength_m
    k = 2.0 * math.pi / lam
    offsets = np.asarray(offsets_m, dtype=float)
    n_d, n_f = offsets.size, len(fam)
    h = tunnel.cross_distance_m
    taps = np.zeros((n_d, n_delay_bins), dtype=complex)
    p_mean = np.zeros(n_d)
    m1 = np.zeros(n_d)
    m2 = np.zeros(n_d)
    if propagation == "physical":  # compiled; its moments come from the local mean below
        eirp = 10.0 ** (cable.slot_eirp_offset_db(tunnel.slot_spacing_m) / 20.0)
        g_grid = _scaled_product_grid(fam, eps, polarization, n_sin_grid) * (eirp * lam / (4.0 * math.pi))
        _physical_taps(
            np.ascontiguousarray(fam.ell_m, dtype=float),
            g_grid,
            np.ascontiguousarray(offsets),
            k,
            h,
            SPEED_OF_LIGHT_M_S,
            delay_bin_s,
            taps,
            p_mean,
        )
    else:
        _source_model_taps(fam, cable, offsets, h, k, source_model, rng, delay_bin_s, chunk, taps, p_mean, m1, m2)
    los = np.sqrt(h * h + offsets**2) / SPEED_OF_LIGHT_M_S
    p_incoherent = p_mean
    lm_desc = "local-mean power gain (incoherent sum over rays, the source's model) "
    if propagation == "physical":
        p_mean, m1, m2, lm_desc = _physical_local_mean(offsets, taps, los, delay_bin_s, local_mean_window_m)
    attrs = {
        "engine": fam.engine,
        "propagation": propagation,
        "polarization": polarization,
        "n_families": n_f,
        "max_reflections": int(fam.n_refl.max(initial=0)),
        "local_mean_window_m": float(local_mean_window_m or 0.0),
        "shape": tunnel.shape,
    }
    return _table_dataset(taps, p_mean, p_incoherent, m1, m2, los, offsets, delay_bin_s, lm_desc, attrs)


def _source_model_taps(
    fam: Families,
    cable: Cable,
    offsets: np.ndarray,
    h: float,
    k: float,
    source_model: SourceModel | None,
    rng: np.random.Generator | None,
    delay_bin_s: float,
    chunk: int,
    taps: np.ndarray,
    p_mean: np.ndarray,
    m1: np.ndarray,
    m2: np.ndarray,
) -> None:
    """The source's model (source 2.2-2.4) into ``taps`` [offset, bin], its incoherent local mean
    ``p_mean`` and the delay moments ``m1``, ``m2`` [offset], ``chunk`` offsets at a time."""
    sm = source_model or SourceModel()
    if rng is None:
        raise ValueError("rng is required for propagation='source' (random multipath loss)")
    fixed_db = -sm.reflection_loss_db * fam.n_refl
    lam = cable.wavelength_m
    n_d, n_delay_bins = taps.shape
    ell = fam.ell_m[:, None]
    for a in range(0, n_d, chunk):
        dx = offsets[a : a + chunk][None, :]
        d = np.sqrt(ell**2 + dx**2)
        d_direct = np.sqrt(h * h + dx**2)
        # the source's random 0-10 dB multipath loss, drawn per reflected ray and per offset,
        # i.e. independently for every slot-receiver pair (source 2.4.2)
        mp_db = np.where(fam.n_refl[:, None] > 0, rng.uniform(0.0, sm.multipath_max_db, d.shape), 0.0)
        loss_db = (
            (
                cable.coupling_loss_at_db(d_direct)
                + 20.0 * np.log10(4.0 * math.pi * d / lam)
                + sm.tunnel_att_db_per_m * d
            )
            - fixed_db[:, None]
            + mp_db
        )
        amp = 10.0 ** (-loss_db / 20.0) * np.exp(-1j * k * d)
        tau = d / SPEED_OF_LIGHT_M_S
        pw = np.abs(amp) ** 2
        p_mean[a : a + chunk] = pw.sum(axis=0)
        m1[a : a + chunk] = (pw * tau).sum(axis=0)
        m2[a : a + chunk] = (pw * tau**2).sum(axis=0)
        b = np.clip(np.rint((tau - d_direct / SPEED_OF_LIGHT_M_S) / delay_bin_s), 0, n_delay_bins - 1)
        nd = dx.shape[1]
        flat = (np.arange(nd)[None, :] * n_delay_bins + b.astype(np.int64)).ravel()
        re = np.bincount(flat, weights=amp.real.ravel(), minlength=nd * n_delay_bins)
        im = np.bincount(flat, weights=amp.imag.ravel(), minlength=nd * n_delay_bins)
        taps[a : a + chunk] = (re + 1j * im).reshape(nd, n_delay_bins)


def _physical_local_mean(
    offsets: np.ndarray, taps: np.ndarray, los: np.ndarray, delay_bin_s: float, local_mean_window_m: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """The physical channel's local mean (the coherent ray sum's power averaged over
    ``local_mean_window_m`` of offsets, mirrored at dx = 0) and the delay moments of the
    local-mean power delay profile [offset], with the local mean's description."""
    n_d, n_delay_bins = taps.shape
    if local_mean_window_m is None or not local_mean_window_m > 0:
        raise ValueError("local_mean_window_m (> 0) is required for propagation='physical'")
    step = offsets[1] - offsets[0] if n_d > 1 else 1.0
    n_win = window_samples(local_mean_window_m, step)
    p_mean = moving_mean(np.abs(taps.sum(axis=1)) ** 2, n_win, mirror_start=True)
    pdp = moving_mean(np.abs(taps) ** 2, n_win, mirror_start=True)
    tau_b = los[:, None] + np.arange(n_delay_bins)[None, :] * delay_bin_s
    p_pdp = pdp.sum(axis=1)
    m1 = (pdp * tau_b).sum(axis=1) * (p_mean / p_pdp)
    m2 = (pdp * tau_b**2).sum(axis=1) * (p_mean / p_pdp)
    lm_desc = f"local-mean power gain (coherent ray sum, power averaged over {local_mean_window_m:g} m) "
    return p_mean, m1, m2, lm_desc


def _table_dataset(
    taps: np.ndarray,
    p_mean: np.ndarray,
    p_incoherent: np.ndarray,
    m1: np.ndarray,
    m2: np.ndarray,
    los: np.ndarray,
    offsets: np.ndarray,
    delay_bin_s: float,
    lm_desc: str,
    attrs: dict,
) -> xr.Dataset:
    """The tabulated channel of :func:`tabulate` [offset] (mean delay and RMS delay spread from
    the moments ``m1``, ``m2`` over ``p_mean``)."""
    n_delay_bins = taps.shape[1]
    mean_tau = m1 / p_mean
    rms = np.sqrt(np.maximum(m2 / p_mean - mean_tau**2, 0.0))
    ds = xr.Dataset(
        {
            "taps": (
                ("offset_m", "excess_delay_s"),
                taps,
                {
                    "units": "1",
                    "long_name": "slot-to-receiver channel taps (amplitude gain "
                    "relative to the cable power at the slot, binned by excess delay)",
                },
            ),
            "power_mean": (
                "offset_m",
                p_mean,
                {"units": "1", "long_name": lm_desc + "relative to the cable power at the slot"},
            ),
            "power_incoherent": (
                "offset_m",
                p_incoherent,
                {
                    "units": "1",
                    "long_name": "incoherent sum of the rays' powers relative to the cable power at the slot",
                },
            ),
            "delay_mean_s": ("offset_m", mean_tau, {"units": "s", "long_name": "power-weighted mean delay"}),
            "delay_rms_s": ("offset_m", rms, {"units": "s", "long_name": "RMS delay spread of one slot"}),
            "los_delay_s": ("offset_m", los, {"units": "s", "long_name": "line-of-sight delay"}),
        },
        coords={
            "offset_m": ("offset_m", offsets, {"units": "m", "long_name": "along-axis offset |x_rx - x_slot|"}),
            "excess_delay_s": (
                "excess_delay_s",
                np.arange(n_delay_bins) * delay_bin_s,
                {"units": "s", "long_name": "excess delay over the line of sight (last bin collects everything later)"},
            ),
        },
        attrs=attrs,
    )
    return ds


# ------------------------------------------------------------------------ assembling
@dataclass
class Received:
    """Sum over slots at receiver positions (arrays over receivers)."""

    rssi_coherent_dbm: np.ndarray
    rssi_mean_dbm: np.ndarray
    delay_rms_s: np.ndarray
    n_strong_rays: np.ndarray


def slot_powers(tunnel: Tunnel, cable: Cable) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Slot x [m], cable power at each slot [dBm], cable delay from its feed [s].

    Parameters
    ----------
    tunnel : Tunnel
        Slot positions and tunnel length.
    cable : Cable
        Feeds, longitudinal loss and velocity factor.

    Returns
    -------
    tuple of numpy.ndarray
        ``(x_slot_m, cable_power_dbm, cable_delay_s)``, each [slot]: the slot positions
        along the tunnel [m], the cable power at each slot [dBm] and the delay from its
        feed along the cable [s].
    """
    xs = tunnel.slot_x_m
    return xs, cable.cable_power_dbm(xs, tunnel.length_m), cable.cable_delay_s(xs, tunnel.length_m)


def offset_index(table: xr.Dataset, dx_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Grid index of |dx| and whether it lies within the table."""
    off = table["offset_m"].values
    step = off[1] - off[0]
    idx = np.rint(np.abs(dx_m) / step).astype(np.int64)
    inside = idx < off.size
    return np.minimum(idx, off.size - 1), inside


def window_slots(tunnel: Tunnel, x_rx_m: np.ndarray, half_width_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the slots within +-half_width of each receiver [rx, n] and a validity mask.

    Parameters
    ----------
    tunnel : Tunnel
        Slot positions and slot spacing.
    x_rx_m : numpy.ndarray
        Receiver positions along the tunnel [m], 1-D [rx].
    half_width_m : float
        Half-width of the window of slots around each receiver [m].

    Returns
    -------
    tuple of numpy.ndarray
        ``(idx, ok)``, each [rx, n] with n = 2 floor(half_width_m / slot spacing) + 2: slot indices (int64, clipped
        to the tunnel's slots) and whether each is a slot of the tunnel within ``half_width_m`` of the receiver.
    """
    xs = tunnel.slot_x_m
    s = tunnel.slot_spacing_m
    n = int(math.floor(half_width_m / s)) * 2 + 2
    first = np.ceil((np.asarray(x_rx_m, dtype=float) - half_width_m) / s - 1e-9).astype(np.int64)
    idx = first[:, None] + np.arange(n)[None, :]
    ok = (idx >= 0) & (idx < xs.size)
    idx_c = np.clip(idx, 0, xs.size - 1)
    ok &= np.abs(np.asarray(x_rx_m)[:, None] - xs[idx_c]) <= half_width_m + 1e-9
    return idx_c, ok


def received(
    table: xr.Dataset, tunnel: Tunnel, cable: Cable, x_rx_m: np.ndarray, strong_dbm: float = -100.0, chunk: int = 2048
) -> Received:
    """RSSI (coherent and local mean), RMS delay spread and the number of rays (taps of
    one slot in one 10-ns delay bin) above ``strong_dbm`` at receiver positions ``x_rx_m``;
    every slot within the table's range contributes.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated slot-to-receiver channel of :func:`tabulate` (``taps``, ``power_mean``,
        ``delay_mean_s``, ``delay_rms_s`` on a uniform ``offset_m`` grid from 0).
    tunnel : Tunnel
        Slot positions and tunnel length.
    cable : Cable
        Cable power and delay at each slot (:func:`slot_powers`) and the carrier frequency.
    x_rx_m : numpy.ndarray
        Receiver positions along the tunnel [m]; each slot-receiver offset is taken at the
        nearest grid offset of the table (exact for receivers on the grid).
    strong_dbm : float
        Received power of one tap above which it counts as a ray [dBm].
    chunk : int
        Receivers evaluated at a time (memory only).

    Returns
    -------
    Received
        Arrays [receiver]: ``rssi_coherent_dbm`` (power of the coherent sum over all slots'
        taps [dBm]), ``rssi_mean_dbm`` (sum over slots of each slot's local-mean power
        [dBm]), ``delay_rms_s`` (RMS delay spread of all slots, cable delays included [s]),
        ``n_strong_rays`` (number of taps above ``strong_dbm`` [1]).
    """
    xs, pc_dbm, tc = slot_powers(tunnel, cable)
    amp_c = 10.0 ** ((pc_dbm - 30.0) / 20.0) * np.exp(-2j * math.pi * cable.frequency_hz * tc)  # sqrt(W)
    taps = table["taps"].values
    h_nb = taps.sum(axis=1)
    tap_w = np.abs(taps) ** 2  # [offset, tap]
    tap_w_max = tap_w.max(axis=1)
    pm = table["power_mean"].values
    mu = table["delay_mean_s"].values
    rms = table["delay_rms_s"].values
    x_rx = np.asarray(x_rx_m, dtype=float)
    out = [np.empty(x_rx.size) for _ in range(4)]
    thr_w = 10.0 ** ((strong_dbm - 30.0) / 10.0)
    max_off = float(table["offset_m"].values[-1])
    for a in range(0, x_rx.size, chunk):
        x = x_rx[a : a + chunk]
        sl, ok = window_slots(tunnel, x, max_off)
        idx, inside = offset_index(table, x[:, None] - xs[sl])
        w = (ok & inside).astype(float)
        ac = amp_c[sl]
        field = (ac * h_nb[idx] * w).sum(axis=1)
        pw = np.abs(ac) ** 2 * pm[idx] * w
        ptot = pw.sum(axis=1)
        tau = tc[sl] + mu[idx]
        m1 = (pw * tau).sum(axis=1)
        m2 = (pw * (rms[idx] ** 2 + tau**2)).sum(axis=1)
        # strong taps: |a_c|^2 |tap|^2 > thr, looked up only for slots whose strongest tap can pass
        pc = np.abs(ac) ** 2
        r, c = np.nonzero((pc * tap_w_max[idx] > thr_w) & (w > 0))
        n_strong = (tap_w[idx[r, c]] * pc[r, c][:, None] > thr_w).sum(axis=1)
        out[0][a : a + chunk] = 10.0 * np.log10(np.abs(field) ** 2) + 30.0
        out[1][a : a + chunk] = 10.0 * np.log10(ptot) + 30.0
        out[2][a : a + chunk] = np.sqrt(np.maximum(m2 / ptot - (m1 / ptot) ** 2, 0.0))
        out[3][a : a + chunk] = np.bincount(r, weights=n_strong, minlength=x.size)
    return Received(*out)
