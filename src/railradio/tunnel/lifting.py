"""3-D rays from the 2-D ray families of :mod:`railradio.tunnel.rays`: the product of the
reflection coefficients along each ray under a polarization rule, :func:`lift` (the exact
3-D rays at any along-axis offset), :func:`trace` (either engine in one call) and the image
method's coherent gain without per-ray arrays.

Polarization: vertical (E along y) at both ends.  ``paraxial``: TM on walls whose normal
is closer to vertical, TE otherwise (the rule for a rectangle, docs/model/tunnel.md §2.1).  ``vector``:
the field vector is tracked and split into its s and p parts at every reflection; the
received amplitude is its projection on the vertical direction made transverse to the
arriving ray.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from railradio.constants import SPEED_OF_LIGHT_M_S
from railradio.tunnel.geometry import Tunnel
from railradio.tunnel.materials import fresnel_te, fresnel_tm
from railradio.tunnel.rays import Families, image_families, sbr_families

POLARIZATIONS = ("paraxial", "vector")


def _perp_vertical(k: np.ndarray) -> np.ndarray:
    """Unit vector along the vertical (y) made transverse to k (fallback z) [..., 3]."""
    e = np.zeros_like(k)
    e[..., 1] = 1.0
    e = e - k[..., 1:2] * k
    nrm = np.linalg.norm(e, axis=-1, keepdims=True)
    fallback = np.zeros_like(k)
    fallback[..., 2] = 1.0
    fallback = fallback - k[..., 2:3] * k
    fallback /= np.maximum(np.linalg.norm(fallback, axis=-1, keepdims=True), 1e-300)
    return np.where(nrm > 1e-9, e / np.maximum(nrm, 1e-300), fallback)


def reflection_product(
    fam: Families, sin_b: np.ndarray, eps: complex | None, polarization: str, return_history: bool = False
):
    """Product of the reflection coefficients G[f, s] at elevations with sin b = ``sin_b``.

    ``paraxial``: prod_k Gamma_{TM or TE}(sin b |u_k . n_k|).  ``vector``: the vertical
    field is tracked through the s/p split of every reflection and projected on the
    receiver's vertical polarization.  With ``return_history`` (vector only) also the
    field magnitude after each reflection [f, s, k] (it can never grow).  ``eps=None``:
    perfectly absorbing walls (G = 0 for every reflected ray).

    Parameters
    ----------
    fam : Families
        2-D ray families from the slot to the receiver (:mod:`railradio.tunnel.rays`).
    sin_b : numpy.ndarray
        Sines of the angle b between the 3-D ray and the tunnel axis, l / d [1]; in [0, 1];
        [s] (the same for every family) or [f, s].
    eps : complex or None
        Relative permittivity of the wall [1] (real part > 1, imaginary part <= 0); None:
        perfectly absorbing walls.
    polarization : {'paraxial', 'vector'}
        Polarization rule (module docstring).
    return_history : bool
        Also return the field magnitude after each reflection (``vector`` rule, or ``eps``
        None: zeros).

    Returns
    -------
    numpy.ndarray or tuple of numpy.ndarray
        G [f, s] (complex) [1]; with ``return_history`` under the ``vector`` rule or with
        ``eps`` None, ``(G, history)`` with ``history`` [f, s, k] [1].

    Raises
    ------
    ValueError
        When ``polarization`` is unknown; when ``eps`` is given and ``sin_b`` lies outside
        [0, 1], is neither [s] nor [f, s], or ``eps`` is not a lossy permittivity as above.
    """
    if polarization not in POLARIZATIONS:
        raise ValueError(f"polarization must be one of {POLARIZATIONS}, got {polarization!r}")
    s = np.asarray(sin_b, dtype=float)
    if eps is None:  # perfectly absorbing walls: only the unreflected ray survives
        shape = (len(fam), s.shape[-1])
        g = np.where((fam.n_refl == 0)[:, None], 1.0 + 0j, 0.0 + 0j) * np.ones(shape)
        return (g, np.zeros((*shape, fam.normal.shape[1]))) if return_history else g
    if np.any(s < 0) or np.any(s > 1):
        raise ValueError("sin_b must be in [0, 1]")
    n_f, r_max = fam.normal.shape[:2]
    s2 = s[None, :] if s.ndim == 1 else s
    if s.ndim != 1 and s2.shape[0] != n_f:
        raise ValueError(f"sin_b must be [s] or [{n_f}, s], got shape {s.shape}")
    n_s = s2.shape[1]
    if polarization == "paraxial" and fam.engine == "image":
        # in the rectangle all floor/ceiling (TM) reflections of a family share one incidence
        # cosine, and all side-wall (TE) ones another: the product is two powers
        n_tm, c_tm, n_te, c_te = image_power_form(fam)
        return (
            fresnel_tm(np.clip(s2 * c_tm[:, None], 0.0, 1.0), eps) ** n_tm[:, None]
            * fresnel_te(np.clip(s2 * c_te[:, None], 0.0, 1.0), eps) ** n_te[:, None]
        )
    if polarization == "paraxial":
        g = np.ones((n_f, n_s), dtype=complex)
        for k in range(r_max):
            act = (fam.n_refl > k)[:, None]
            if not np.any(act):
                break
            u, nrm = fam.direction[:, k], fam.normal[:, k]
            c2d = np.abs(np.einsum("ij,ij->i", u, nrm))[:, None]
            cos_i = np.clip(s2 * c2d, 0.0, 1.0)
            vertical = (np.abs(nrm[:, 0]) >= np.abs(nrm[:, 1]))[:, None]
            gam = np.where(vertical, fresnel_tm(cos_i, eps), fresnel_te(cos_i, eps))
            g = np.where(act, g * gam, g)
        return g
    return _vector_product(fam, s2, eps, return_history)


def _vector_product(fam: Families, s2: np.ndarray, eps: complex, return_history: bool):
    """The ``vector`` rule of :func:`reflection_product` at sin b = ``s2`` [1 or f, s]."""
    n_f, r_max = fam.normal.shape[:2]
    n_s = s2.shape[1]
    cb = np.sqrt(np.maximum(1.0 - s2**2, 0.0))

    def k3(u2):  # [f, 2] -> [f, s, 3]
        return np.stack([np.broadcast_to(cb, (n_f, n_s)), s2 * u2[:, 0:1], s2 * u2[:, 1:2]], axis=-1)

    first = fam.direction[:, 0] if r_max else fam.final_direction
    first = np.where((fam.n_refl > 0)[:, None], first, fam.final_direction)
    kvec = k3(first)
    e = _perp_vertical(kvec).astype(complex)
    hist = np.zeros((n_f, n_s, r_max)) if return_history else None
    for k in range(r_max):
        act = (fam.n_refl > k)[:, None]
        if not np.any(act):
            break
        kin = k3(fam.direction[:, k])
        n3 = np.zeros((n_f, 1, 3))
        n3[:, 0, 1:] = fam.normal[:, k]
        n3 = np.broadcast_to(n3, kin.shape)
        cos_i = np.clip(-np.einsum("fsi,fsi->fs", kin, n3), 0.0, 1.0)
        sv = np.cross(kin, n3)
        sn = np.linalg.norm(sv, axis=-1, keepdims=True)
        xhat = np.zeros_like(sv)
        xhat[..., 0] = 1.0
        sv = np.where(sn > 1e-9, sv / np.maximum(sn, 1e-300), xhat)
        kout = kin - 2.0 * np.einsum("fsi,fsi->fs", kin, n3)[..., None] * n3
        p_in, p_out = np.cross(sv, kin), np.cross(sv, kout)
        es = np.einsum("fsi,fsi->fs", e, sv)
        ep = np.einsum("fsi,fsi->fs", e, p_in)
        e_new = (fresnel_te(cos_i, eps) * es)[..., None] * sv + (fresnel_tm(cos_i, eps) * ep)[..., None] * p_out
        e = np.where(act[..., None], e_new, e)
        if return_history:
            hist[:, :, k] = np.linalg.norm(e, axis=-1)
    rvec = _perp_vertical(k3(fam.final_direction))
    g = np.einsum("fsi,fsi->fs", e, rvec)
    return (g, hist) if return_history else g


@dataclass
class Rays:
    """Per-ray result of :func:`trace`: arrays [ray, offset]."""

    amplitude: np.ndarray
    """complex amplitude relative to an isotropic source of unit EIRP (free space: lambda/(4 pi d))"""
    delay_s: np.ndarray
    """delay d / c along the 3-D ray from the slot [s]"""
    n_reflections: np.ndarray
    """[ray]"""


def lift(fam: Families, dx_m, wavelength_m: float, eps: complex, polarization: str) -> Rays:
    """3-D rays of every family at along-axis offsets ``dx_m`` (exact, no grid).

    Parameters
    ----------
    fam : Families
        2-D ray families from the slot to the receiver (:mod:`railradio.tunnel.rays`).
    dx_m : float or array_like
        Along-axis offsets x_rx - x_slot [m] (only |dx| matters), 1-D.
    wavelength_m : float
        Free-space wavelength [m].
    eps : complex or None
        Relative permittivity of the wall [1] (real part > 1, imaginary part <= 0);
        None: perfectly absorbing walls (every reflected ray has amplitude 0).
    polarization : {'paraxial', 'vector'}
        Polarization rule of the reflection product (module docstring).

    Returns
    -------
    Rays
        ``amplitude`` [ray, offset] (complex, relative to an isotropic source of unit EIRP
        [1]), ``delay_s`` [ray, offset] (delay from the slot [s]), ``n_reflections`` [ray].

    Raises
    ------
    ValueError
        When ``polarization`` is unknown or ``eps`` is not a lossy permittivity as above.
    """
    dx = np.abs(np.asarray(dx_m, dtype=float))[None, :]
    ell = fam.ell_m[:, None]
    d = np.sqrt(ell**2 + dx**2)
    out = reflection_product(fam, ell / d, eps, polarization)
    k = 2.0 * math.pi / wavelength_m
    amp = (
        out
        * fam.spread[:, None]
        * np.exp(1j * fam.caustic_phase_rad[:, None])
        * wavelength_m
        / (4.0 * math.pi * d)
        * np.exp(-1j * k * d)
    )
    return Rays(amp, d / SPEED_OF_LIGHT_M_S, fam.n_refl.copy())


ENGINES = ("image", "sbr")


def trace(
    engine: str,
    tunnel: Tunnel,
    dx_m,
    wavelength_m: float,
    eps: complex,
    order: int,
    polarization: str | None = None,
    n_rays: int = 100_000,
    rx_radius_m: float = 0.1,
) -> Rays:
    """One interface to both engines: rays from a slot to the receiver at offsets dx.

    ``image`` needs a rectangular tunnel; ``sbr`` takes either cross-section.  The
    polarization rule defaults to paraxial for the image method, vector for SBR.

    Parameters
    ----------
    engine : {'image', 'sbr'}
        Ray engine (:func:`~railradio.tunnel.rays.image_families`,
        :func:`~railradio.tunnel.rays.sbr_families`).
    tunnel : Tunnel
        The tunnel; ``'rect'`` for the image method.
    dx_m : array_like
        Along-axis offsets x_rx - x_slot [m] (only |dx| matters), 1-D.
    wavelength_m : float
        Free-space wavelength [m].
    eps : complex or None
        Relative permittivity of the wall [1] (real part > 1, imaginary part <= 0); None:
        perfectly absorbing walls.
    order : int
        Largest reflection order (image: |m| + |n|; SBR: reflections traced) [1].
    polarization : {'paraxial', 'vector'} or None
        Polarization rule; None: the engine's default.
    n_rays : int
        2-D rays launched by SBR; >= 16.
    rx_radius_m : float
        Radius of SBR's reception circle around the receiver [m].

    Returns
    -------
    Rays
        The rays of :func:`lift`: ``amplitude`` [ray, offset] [1], ``delay_s`` [ray, offset]
        [s], ``n_reflections`` [ray].

    Raises
    ------
    ValueError
        When ``engine`` is unknown, or the engine or :func:`lift` rejects its arguments.
    """
    if engine == "image":
        fam = image_families(tunnel, order)
    elif engine == "sbr":
        fam = sbr_families(tunnel, n_rays, order, rx_radius_m)
    else:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    pol = polarization or ("paraxial" if engine == "image" else "vector")
    return lift(fam, dx_m, wavelength_m, eps, pol)


@njit(cache=True, nogil=True)
def _image_sum(ell, n_tm, c_tm, n_te, c_te, dx, k, eps, out):
    """out[order, j] += every family's ray at offset dx[j], by its reflection order."""
    for j in range(dx.size):
        for f in range(ell.size):
            d = math.sqrt(ell[f] * ell[f] + dx[j] * dx[j])
            s = ell[f] / d
            g = 1.0 + 0j
            if n_tm[f] > 0:
                c = s * c_tm[f]
                r = cmath.sqrt(eps - (1.0 - c * c))
                g *= ((eps * c - r) / (eps * c + r)) ** n_tm[f]
            if n_te[f] > 0:
                c = s * c_te[f]
                r = cmath.sqrt(eps - (1.0 - c * c))
                g *= ((c - r) / (c + r)) ** n_te[f]
            out[n_tm[f] + n_te[f], j] += g * cmath.exp(-1j * k * d) / d


def image_power_form(fam: Families) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """An image family's reflections in the rectangle, counted by wall pair: (number of
    floor/ceiling reflections, their 2-D incidence cosine |u_y|, number of side-wall
    reflections, |u_z|) per family (the 2-D direction only changes sign at a reflection).

    Parameters
    ----------
    fam : Families
        Image-method families (:func:`~railradio.tunnel.rays.image_families`).

    Returns
    -------
    tuple of numpy.ndarray
        ``(n_tm, c_tm, n_te, c_te)``, each [f]: floor/ceiling reflections (int64), their 2-D
        incidence cosine |u_y| [1], side-wall reflections (int64), their cosine |u_z| [1].
    """
    valid = np.arange(fam.normal.shape[1])[None, :] < fam.n_refl[:, None]
    on_floor = valid & (np.abs(fam.normal[..., 0]) >= np.abs(fam.normal[..., 1]))
    n_tm = on_floor.sum(axis=1).astype(np.int64)
    n_te = (fam.n_refl - n_tm).astype(np.int64)
    return (
        n_tm,
        np.abs(fam.final_direction[:, 0]).astype(float),
        n_te,
        np.abs(fam.final_direction[:, 1]).astype(float),
    )


def image_coherent_gain(fam: Families, dx_m, wavelength_m: float, eps: complex, by_order: bool = False) -> np.ndarray:
    """Coherent (narrowband) gain of one slot in the rectangular tunnel, the sum of every
    image family's ray, at offsets ``dx_m`` (complex, relative to unit EIRP): exactly
    :func:`lift` (paraxial rule) summed over rays, without its [ray, offset] arrays.  In the
    rectangle every reflection off the floor or ceiling (TM) has the incidence cosine
    sin b |u_y|, off a side wall (TE) sin b |u_z|, so the product is two powers.
    ``by_order``: the sum of each reflection order apart, [order 0..max, offset] (its
    cumulative sum over orders is the gain truncated at each order).

    Parameters
    ----------
    fam : Families
        Image-method families (:func:`~railradio.tunnel.rays.image_families`).
    dx_m : array_like
        Along-axis offsets x_rx - x_slot [m] (only |dx| matters; flattened).
    wavelength_m : float
        Free-space wavelength [m].
    eps : complex
        Relative permittivity of the wall [1] (real part > 1, imaginary part <= 0).
    by_order : bool
        Return each reflection order's sum apart.

    Returns
    -------
    numpy.ndarray
        Complex gain relative to unit EIRP [1]: [offset], or [order 0..max, offset] with
        ``by_order``.

    Raises
    ------
    ValueError
        When ``fam`` does not come from the image method or ``eps`` is None.
    """
    if fam.engine != "image":
        raise ValueError(f"fam must come from image_families, got engine {fam.engine!r}")
    if eps is None:
        raise ValueError("eps is required")
    dx = np.ascontiguousarray(np.abs(np.asarray(dx_m, dtype=float)).ravel())
    n_tm, c_tm, n_te, c_te = image_power_form(fam)
    out = np.zeros((int(fam.n_refl.max(initial=0)) + 1, dx.size), dtype=complex)
    _image_sum(
        np.ascontiguousarray(fam.ell_m, dtype=float),
        n_tm,
        c_tm,
        n_te,
        c_te,
        dx,
        2.0 * math.pi / wavelength_m,
        complex(eps),
        out,
    )
    out *= wavelength_m / (4.0 * math.pi)
    return out if by_order else out.sum(axis=0)
