"""The field of one slot as a sum of lossy waveguide modes: EH_mn in the square tunnel
(Emslie, Lagace & Strong 1975), the reference the image method's far field is checked
against, and the modes of the hollow circular guide in the circle (Marcatili & Schmeltzer
1964), the circle's far field (docs/model/tunnel.md §2.2).

Far from the slot every ray grazes the walls, where both Fresnel coefficients tend to -1, so
the image sum becomes the Dirichlet Green's function of the rectangle, whose modal
expansion is

    G(x; s, r) = sum_mn phi_mn(s) phi_mn(r) exp(-(alpha_mn + j beta_mn) |x|) / (2 j beta_mn),
    phi_mn(y, z) = (2 / sqrt(w h)) sin(m pi (z + w/2) / w) sin(n pi y / h),

with beta_mn = sqrt(k^2 - (m pi / w)^2 - (n pi / h)^2) and the wall loss of each mode for a
vertical field (Emslie et al. 1975, eq. 7 with the polarizations swapped)

    alpha_mn = (lambda^2 / 2) Re[ m^2 / (w^3 sqrt(eps - 1)) + n^2 eps / (h^3 sqrt(eps - 1)) ]  [Np/m]

(side walls TE, floor and ceiling TM).  A ray of the image method carries
lambda e^{-jkd} / (4 pi d) per unit EIRP, i.e. lambda times the free-space Green's function,
so the modal gain is lambda G: the two are on the same scale and can be compared directly.

In the circle of radius a (polar angle phi from the horizontal z axis, y - a = r sin phi) the
same grazing limit gives the Dirichlet modes of the disk, psi = J_l(u r / a) cos(l phi) or
sin(l phi) with J_l(u) = 0, norm pi a^2 J_{l+1}(u)^2 (l = 0) or half of it (l >= 1), phase
constant sqrt(k^2 - (u/a)^2).  Each is the vertical component of Marcatili & Schmeltzer's
vector modes, whose loss is (u / 2 pi)^2 lambda^2 / a^3 Re(nu) [Np/m] (their eq. 35), with
nu = 1/sqrt(eps - 1) (TE_0m), eps/sqrt(eps - 1) (TM_0m) and (eps + 1)/(2 sqrt(eps - 1))
(hybrid EH_nm, n != 0):

- l = 0: EH_1m, linearly polarized;
- l = 1: the vertical field J_1 cos(phi) is half TE_0m (its uniform azimuthal part) and half
  EH_2m; J_1 sin(phi) is half TM_0m (its uniform radial part) and half EH_2m: the two halves
  decay at their own rates (same phase constant);
- l >= 2: EH_{l+1,m} and EH_{-(l-1),m}, both hybrid: one loss.
"""

from __future__ import annotations

import math

import numpy as np

from railradio.tunnel.geometry import Tunnel


def rect_mode_attenuation_np_per_m(
    m: np.ndarray, n: np.ndarray, wavelength_m: float, width_m: float, height_m: float, eps: complex
) -> np.ndarray:
    """Wall loss of the vertically polarized modes EH_mn of a rectangular tunnel [Np/m]
    (module docstring; m counts the half-waves across the width, n across the height).

    Parameters
    ----------
    m, n : numpy.ndarray
        Mode indices, >= 1, broadcastable.
    wavelength_m : float
        Free-space wavelength [m]; positive.
    width_m, height_m : float
        Width (between the side walls) and height (floor to ceiling) [m]; positive.
    eps : complex
        Relative permittivity of the walls [1] (imaginary part <= 0).

    Returns
    -------
    numpy.ndarray
        Amplitude attenuation [Np/m], the broadcast shape of ``m`` and ``n``.

    Raises
    ------
    ValueError
        When a length is not positive.
    """
    if not (wavelength_m > 0 and width_m > 0 and height_m > 0):
        raise ValueError("wavelength_m, width_m and height_m must be positive")
    root = np.sqrt(complex(eps) - 1.0)
    te = np.real(1.0 / root) / width_m**3
    tm = np.real(eps / root) / height_m**3
    return 0.5 * wavelength_m**2 * (np.asarray(m, dtype=float) ** 2 * te + np.asarray(n, dtype=float) ** 2 * tm)


def rect_modal_gain(
    tunnel: Tunnel, x_m: np.ndarray, wavelength_m: float, eps: complex, max_index: int | None = None
) -> np.ndarray:
    """One slot's complex gain at the receiver (unit EIRP, the image method's scale) as the
    sum of the propagating lossy modes of the square tunnel, at axial offsets ``x_m``.

    Parameters
    ----------
    tunnel : Tunnel
        A tunnel of shape ``rect``: its width, height, slot and receiver cross-section positions.
    x_m : numpy.ndarray
        Axial offsets from the slot [m], 1-D; far from the slot (many wavelengths; the
        evanescent modes are left out).
    wavelength_m : float
        Free-space wavelength [m]; positive.
    eps : complex
        Relative permittivity of the walls [1].
    max_index : int or None
        Largest m and n summed; None: every propagating mode (m < 2 w / lambda).

    Returns
    -------
    numpy.ndarray
        Complex gain [x] [1], comparable with :func:`railradio.tunnel.rays.image_coherent_gain`.

    Raises
    ------
    ValueError
        When the tunnel is not rectangular or ``max_index`` < 1.
    """
    if tunnel.shape != "rect":
        raise ValueError(f"the modal sum needs a rectangular tunnel, got shape {tunnel.shape!r}")
    w, h = tunnel.width_m, tunnel.height_m
    k = 2.0 * math.pi / wavelength_m
    n_max = int(math.floor(2.0 * min(w, h) / wavelength_m - 1e-9)) if max_index is None else int(max_index)
    if n_max < 1:
        raise ValueError(f"max_index must be >= 1, got {max_index!r}")
    idx = np.arange(1, n_max + 1)
    m, n = np.meshgrid(idx, idx, indexing="ij")
    kt2 = (m * math.pi / w) ** 2 + (n * math.pi / h) ** 2
    prop = kt2 < k * k
    m, n, kt2 = m[prop], n[prop], kt2[prop]
    beta = np.sqrt(k * k - kt2)
    alpha = rect_mode_attenuation_np_per_m(m, n, wavelength_m, w, h, eps)
    (ys, zs), (yr, zr) = tunnel.slot_yz, tunnel.rx_yz
    phi_s = np.sin(m * math.pi * (zs + w / 2.0) / w) * np.sin(n * math.pi * ys / h)
    phi_r = np.sin(m * math.pi * (zr + w / 2.0) / w) * np.sin(n * math.pi * yr / h)
    coef = (4.0 / (w * h)) * phi_s * phi_r / (2j * beta) * wavelength_m  # lambda G's modal weights
    x = np.abs(np.asarray(x_m, dtype=float))
    out = np.empty(x.size, dtype=complex)
    for a in range(0, x.size, 2048):
        xa = x[a : a + 2048, None]
        out[a : a + 2048] = np.exp(-(alpha + 1j * beta)[None, :] * xa) @ coef
    return out


CIRCLE_NU = ("te", "tm", "hybrid")
"""Wall-impedance kinds of the circular guide's modes (Marcatili & Schmeltzer 1964, eq. 35)."""


def _circle_nu(eps: complex) -> dict[str, float]:
    root = np.sqrt(complex(eps) - 1.0)
    return {
        "te": float(np.real(1.0 / root)),
        "tm": float(np.real(eps / root)),
        "hybrid": float(np.real((eps + 1.0) / (2.0 * root))),
    }


def circle_modes(tunnel: Tunnel, wavelength_m: float, eps: complex) -> dict[str, np.ndarray]:
    """The propagating modes of the circular tunnel that carry one slot's vertical field to
    the receiver (module docstring): for every mode with a non-zero weight, its phase
    constant, its weight in lambda G, and the losses of its (at most two) vector parts.

    Parameters
    ----------
    tunnel : Tunnel
        A tunnel of shape ``circle``: its diameter, slot and receiver cross-section positions.
    wavelength_m : float
        Free-space wavelength [m]; positive.
    eps : complex
        Relative permittivity of the walls [1].

    Returns
    -------
    dict
        ``beta`` [mode] (phase constant) [rad/m], ``coef`` [mode] (weight of the mode in lambda G
        before its exp(-(alpha + j beta)|x|)) [m], ``alpha`` [mode, 2] (loss of each vector part)
        [Np/m], ``share`` [mode, 2] (the parts' shares of the mode's field, summing to 1) [1],
        ``l`` and ``u`` [mode] (azimuthal order, Bessel zero) [1].

    Raises
    ------
    ValueError
        When the tunnel is not circular or the wavelength is not positive.
    """
    from scipy.special import jn_zeros, jv

    if tunnel.shape != "circle":
        raise ValueError(f"the circular modal sum needs a circular tunnel, got shape {tunnel.shape!r}")
    if not wavelength_m > 0:
        raise ValueError(f"wavelength_m must be positive, got {wavelength_m!r}")
    a = tunnel.diameter_m / 2.0
    ka = 2.0 * math.pi / wavelength_m * a
    nu = _circle_nu(eps)
    (ys, zs), (yr, zr) = tunnel.slot_yz, tunnel.rx_yz
    rs, ps = math.hypot(ys - a, zs), math.atan2(ys - a, zs)
    rr, pr = math.hypot(yr - a, zr), math.atan2(yr - a, zr)
    rows = []
    for ell in range(int(ka) + 1):
        us = jn_zeros(ell, int(ka / math.pi) + 2)
        us = us[us < ka]
        for u in us:
            f = jv(ell, u * rs / a) * jv(ell, u * rr / a) / (math.pi * a * a * jv(ell + 1, u) ** 2)
            if ell == 0:
                rows.append((ell, u, f, ("hybrid", "hybrid")))
                continue
            for trig, pure in ((math.cos, "te"), (math.sin, "tm")):
                parts = (pure if ell == 1 else "hybrid", "hybrid")
                rows.append((ell, u, 2.0 * f * trig(ell * ps) * trig(ell * pr), parts))
    rows = [r for r in rows if abs(r[2]) > 1e-12 * max(abs(q[2]) for q in rows)]
    ell = np.array([r[0] for r in rows])
    u = np.array([r[1] for r in rows])
    k = 2.0 * math.pi / wavelength_m
    beta = np.sqrt(k * k - (u / a) ** 2)
    scale = (u / (2.0 * math.pi)) ** 2 * wavelength_m**2 / a**3
    alpha = np.array([[nu[r[3][0]], nu[r[3][1]]] for r in rows]) * scale[:, None]
    coef = np.array([r[2] for r in rows]) / (2j * beta) * wavelength_m
    return {"beta": beta, "coef": coef, "alpha": alpha, "share": np.full(alpha.shape, 0.5), "l": ell, "u": u}


def circle_modal_gain(tunnel: Tunnel, x_m: np.ndarray, wavelength_m: float, eps: complex) -> np.ndarray:
    """One slot's complex gain at the receiver (unit EIRP, the ray engines' scale) as the
    sum of the propagating lossy modes of the circular tunnel (:func:`circle_modes`), at
    axial offsets ``x_m``.

    Parameters
    ----------
    tunnel : Tunnel
        A tunnel of shape ``circle``.
    x_m : numpy.ndarray
        Axial offsets from the slot [m], 1-D; far from the slot (the evanescent modes are
        left out and the losses are the grazing limit's).
    wavelength_m : float
        Free-space wavelength [m]; positive.
    eps : complex
        Relative permittivity of the walls [1].

    Returns
    -------
    numpy.ndarray
        Complex gain [x] [1].

    Raises
    ------
    ValueError
        When the tunnel is not circular or the wavelength is not positive.
    """
    m = circle_modes(tunnel, wavelength_m, eps)
    x = np.abs(np.asarray(x_m, dtype=float))
    out = np.empty(x.size, dtype=complex)
    for a in range(0, x.size, 2048):
        xa = x[a : a + 2048, None]
        att = (m["share"][None, :, :] * np.exp(-m["alpha"][None, :, :] * xa[:, :, None])).sum(axis=2)
        out[a : a + 2048] = (np.exp(-1j * m["beta"][None, :] * xa) * att) @ m["coef"]
    return out
