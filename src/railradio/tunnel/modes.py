"""The field of one slot in the square tunnel as a sum of lossy waveguide modes EH_mn
(Emslie, Lagace & Strong 1975), the reference the ray engine's far field is checked against
(docs/model/tunnel.md §2.2).

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
