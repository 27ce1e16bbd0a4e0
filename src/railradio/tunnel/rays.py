"""Two ray engines behind one interface: image method and shooting-and-bouncing rays.

A straight tunnel is invariant along its axis x and every wall normal lies in the
cross-section (y, z).  A 3-D ray with direction (cos b, sin b u), u a unit vector in the
cross-section, therefore moves in (y, z) exactly like a 2-D ray with direction u bouncing
in the cross-section (a billiard), while x advances analytically.  Both engines find the
2-D *ray families* from the slot to the receiver in the cross-section (:class:`Families`:
2-D path length l, the wall normal and 2-D direction at every reflection, a 2-D spreading
factor); :func:`railradio.tunnel.lifting.lift` turns a family into the 3-D ray for any
along-axis offset dx:

    d = sqrt(l^2 + dx^2),  sin b = l / d,  cos(incidence)_k = sin b |u_k . n_k|
    a = G(sin b) sqrt(l / J) lambda / (4 pi d) exp(-j k d) exp(j pi/2 N_caustic),  tau = d / c

with G the product of the reflection coefficients along the ray (its polarization rules:
:mod:`railradio.tunnel.lifting`) and J the 2-D ray-tube width per radian (J = l for planar
walls).  Per ray: complex amplitude (relative to an isotropic source of unit EIRP), delay,
number of reflections.

Engines:

* :func:`image_families` - image method in the rectangular tunnel (exact), reflection
  order |m| + |n| <= order.
* :func:`sbr_families` - shooting and bouncing rays in the circular (or rectangular)
  cross-section, vectorized over rays: N rays launched uniformly in angle, a reception
  circle of radius r around the receiver (in 3-D a reception cylinder along x, which the
  translation invariance makes exact); captured rays are grouped into families (adjacent
  launch angles with the same number of reflections), the central ray of each family is
  found by interpolating the signed miss distance to zero and re-traced, and the tube
  width J follows from the slope of the miss distance over launch angle (the count of
  rays in the circle bounds it at caustics).  The 2-D caustic count is approximated by
  its parity (the orientation of the tube).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from railradio.tunnel.geometry import Tunnel


@dataclass
class Families:
    """2-D ray families from the slot to the receiver in the cross-section.

    Arrays over families f and reflections k (padded beyond ``n_refl[f]``):
    ``ell_m[f]`` 2-D path length [m]; ``n_refl[f]``; ``normal[f, k, 2]`` inward unit
    normal (y, z) of the k-th reflection; ``direction[f, k, 2]`` 2-D unit direction of
    the ray arriving at it; ``final_direction[f, 2]`` at the receiver; ``spread[f]``
    = sqrt(l / J) (1 for planar walls); ``caustic_phase_rad[f]``.
    """

    ell_m: np.ndarray
    n_refl: np.ndarray
    normal: np.ndarray
    direction: np.ndarray
    final_direction: np.ndarray
    spread: np.ndarray
    caustic_phase_rad: np.ndarray
    engine: str
    stats: dict

    def __len__(self) -> int:
        return int(self.ell_m.size)

    def subset(self, mask: np.ndarray) -> Families:
        """The families selected by ``mask``, with the same engine and a copy of ``stats``.

        Parameters
        ----------
        mask : numpy.ndarray
            Boolean mask over the families [f], or the indices of the families to keep.

        Returns
        -------
        Families
            The selected families, in the order ``mask`` gives them.
        """
        m = np.asarray(mask)
        return Families(
            self.ell_m[m],
            self.n_refl[m],
            self.normal[m],
            self.direction[m],
            self.final_direction[m],
            self.spread[m],
            self.caustic_phase_rad[m],
            self.engine,
            dict(self.stats),
        )


# --------------------------------------------------------------------------- image method
def _axis_images(s: float, a: float, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Images of a source at s between walls at 0 and a with at most ``order`` reflections:
    positions and reflection counts (see :func:`image_families`)."""
    pos, cnt = [s], [0]
    for k in range(-order, order + 1):
        if k != 0 and 2 * abs(k) <= order:
            pos.append(2 * k * a + s), cnt.append(2 * abs(k))
        if abs(2 * k - 1) <= order:
            pos.append(2 * k * a - s), cnt.append(abs(2 * k - 1))
    return np.array(pos), np.array(cnt)


def _wall_crossings(
    img_y: np.ndarray,
    dy: np.ndarray,
    n_y: np.ndarray,
    h: float,
    img_z: np.ndarray,
    dz: np.ndarray,
    n_z: np.ndarray,
    w: float,
    order: int,
    r_max: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Parameters t in (0, 1) where each image's unfolded line crosses y = jH and z = jW
    [image, crossing] (inf where it has no more) and whether each crossing is off a y wall."""
    n = img_y.size
    t_all = np.full((n, r_max), np.inf)
    is_y = np.zeros((n, r_max), dtype=bool)
    col = np.zeros(n, dtype=int)
    for which, start, delta, cnt, a in (("y", img_y, dy, n_y, h), ("z", img_z, dz, n_z, w)):
        for j in range(1, order + 1):
            has = cnt >= j
            if not np.any(has):
                continue
            sgn = np.sign(delta[has])
            # j-th wall plane crossed going from the image toward the receiver
            first = np.where(sgn > 0, np.ceil(start[has] / a + 1e-12), np.floor(start[has] / a - 1e-12))
            plane = (first + sgn * (j - 1)) * a
            t = (plane - start[has]) / delta[has]
            rows = np.nonzero(has)[0]
            t_all[rows, col[rows]] = t
            is_y[rows, col[rows]] = which == "y"
            col[rows] += 1
    return t_all, is_y


def image_families(tunnel: Tunnel, order: int) -> Families:
    """All images of the slot in the rectangular tunnel with |m| + |n| <= ``order``.

    Walls y = 0 (floor), y = H (ceiling), z = -W/2, z = +W/2.  Along one axis with walls
    at 0 and A and the source at s, the images are 2kA + s (2|k| reflections) and
    2kA - s (|2k - 1| reflections).  The reflection sequence of each image (which wall,
    in which order) follows from where the unfolded straight line crosses the walls.

    Parameters
    ----------
    tunnel : Tunnel
        The tunnel; its cross-section must be ``'rect'``.
    order : int
        Largest reflection order |m| + |n| [1]; a non-negative integer.

    Returns
    -------
    Families
        One family per image, sorted by reflection count and then 2-D length; planar
        walls, so ``spread`` = 1 and ``caustic_phase_rad`` = 0; ``engine`` 'image',
        ``stats`` {'order', 'n_families'}.

    Raises
    ------
    ValueError
        When ``tunnel.shape`` is not 'rect' or ``order`` is not a non-negative integer.
    """
    if tunnel.shape != "rect":
        raise ValueError("tunnel.shape must be 'rect' for the image method")
    if not isinstance(order, (int, np.integer)) or order < 0:
        raise ValueError(f"order must be a non-negative integer, got {order!r}")
    h, w = tunnel.height_m, tunnel.width_m
    (ys, zs), (yr, zr) = tunnel.slot_yz, tunnel.rx_yz
    zs0, zr0 = zs + w / 2.0, zr + w / 2.0  # shift so the z walls are at 0 and W
    py, ny = _axis_images(ys, h, order)
    pz, nz = _axis_images(zs0, w, order)
    iy, iz = np.meshgrid(np.arange(py.size), np.arange(pz.size), indexing="ij")
    iy, iz = iy.ravel(), iz.ravel()
    keep = ny[iy] + nz[iz] <= order
    iy, iz = iy[keep], iz[keep]
    img_y, img_z = py[iy], pz[iz]
    n_y, n_z = ny[iy], nz[iz]
    n_tot = n_y + n_z
    dy, dz = yr - img_y, zr0 - img_z
    ell = np.hypot(dy, dz)
    uy, uz = dy / ell, dz / ell
    # parameters t in (0, 1) where the unfolded line crosses y = jH and z = jW
    r_max = max(int(n_tot.max(initial=0)), 1)
    t_all, is_y = _wall_crossings(img_y, dy, n_y, h, img_z, dz, n_z, w, order, r_max)
    order_idx = np.argsort(t_all, axis=1, kind="stable")
    is_y = np.take_along_axis(is_y, order_idx, axis=1)
    valid = np.arange(r_max)[None, :] < n_tot[:, None]
    # real-space direction before each reflection: flip the sign of a component per
    # reflection off a wall of that kind that came before
    flips_y = np.cumsum(is_y & valid, axis=1) - (is_y & valid)
    flips_z = np.cumsum(~is_y & valid, axis=1) - (~is_y & valid)
    d_y = uy[:, None] * (-1.0) ** flips_y
    d_z = uz[:, None] * (-1.0) ** flips_z
    normal = np.zeros((ell.size, r_max, 2))
    normal[..., 0] = np.where(is_y, -np.sign(d_y), 0.0)
    normal[..., 1] = np.where(is_y, 0.0, -np.sign(d_z))
    normal[~valid] = (1.0, 0.0)
    direction = np.stack([d_y, d_z], axis=-1)
    final = np.stack([uy * (-1.0) ** n_y, uz * (-1.0) ** n_z], axis=-1)
    srt = np.lexsort((ell, n_tot))
    fam = Families(
        ell[srt],
        n_tot[srt],
        normal[srt],
        direction[srt],
        final[srt],
        np.ones(ell.size),
        np.zeros(ell.size),
        "image",
        {"order": int(order), "n_families": int(ell.size)},
    )
    return fam


# ----------------------------------------------------------------------------- SBR in 2-D
def _wall_hit(tunnel: Tunnel, p: np.ndarray, u: np.ndarray):
    """Distance to the wall along u from p (inside) and the inward normal there."""
    if tunnel.shape == "circle":
        r = tunnel.diameter_m / 2.0
        q = p - np.array([r, 0.0])
        b = np.einsum("ij,ij->i", q, u)
        c = np.einsum("ij,ij->i", q, q) - r * r
        t = -b + np.sqrt(np.maximum(b * b - c, 0.0))
        hit = p + t[:, None] * u
        normal = (np.array([r, 0.0]) - hit) / r
        return t, normal
    h, w = tunnel.height_m, tunnel.width_m
    with np.errstate(divide="ignore", invalid="ignore"):
        ty = np.where(u[:, 0] > 0, (h - p[:, 0]) / u[:, 0], np.where(u[:, 0] < 0, -p[:, 0] / u[:, 0], np.inf))
        tz = np.where(
            u[:, 1] > 0, (w / 2 - p[:, 1]) / u[:, 1], np.where(u[:, 1] < 0, (-w / 2 - p[:, 1]) / u[:, 1], np.inf)
        )
    use_y = ty <= tz
    t = np.maximum(np.where(use_y, ty, tz), 0.0)
    normal = np.zeros_like(p)
    normal[:, 0] = np.where(use_y, -np.sign(u[:, 0]), 0.0)
    normal[:, 1] = np.where(use_y, 0.0, -np.sign(u[:, 1]))
    return t, normal


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def trace_2d(tunnel: Tunnel, phi: np.ndarray, max_refl: int, rx_radius_m: float, history: bool = False):
    """Trace 2-D rays launched from the slot at angles ``phi`` (from +y toward +z).

    Returns the captures (ray index, reflections so far, path length at the closest
    approach, signed miss distance) and, with ``history``, per ray the normals and
    directions at each reflection [n_rays, max_refl, 2].

    Parameters
    ----------
    tunnel : Tunnel
        The tunnel: cross-section, slot and receiver positions (y, z).
    phi : numpy.ndarray
        Launch angles [rad] measured from +y toward +z, [n_rays].
    max_refl : int
        Number of reflections traced; a ray is tested for capture on each of its
        ``max_refl + 1`` straight legs.
    rx_radius_m : float
        Radius of the reception circle around the receiver [m].
    history : bool
        Also return the wall normals and ray directions at every reflection.

    Returns
    -------
    captures : tuple of numpy.ndarray
        ``(j, nb, ell_m, miss_m)``, each [capture], one capture per leg that passes within
        ``rx_radius_m`` of the receiver: the ray index into ``phi``, the number of
        reflections before that leg, the path length to the point of closest approach [m],
        and the signed distance of the receiver from the ray (u x (rx - p)) [m].
    history : tuple
        ``(normals, directions)``, each [n_rays, max_refl, 2]: the inward unit normal (y, z)
        of the wall at every reflection and the unit direction of the ray arriving at it;
        ``(None, None)`` without ``history``.
    """
    n = phi.size
    p = np.tile(np.asarray(tunnel.slot_yz, dtype=float), (n, 1))
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    rx = np.asarray(tunnel.rx_yz, dtype=float)
    length = np.zeros(n)
    caps = []
    normals = np.zeros((n, max_refl, 2)) if history else None
    dirs = np.zeros((n, max_refl, 2)) if history else None
    for b in range(max_refl + 1):
        t, nrm = _wall_hit(tunnel, p, u)
        wv = rx - p
        s = np.einsum("ij,ij->i", wv, u)
        m = _cross(u, wv)
        hit = (s > 0.0) & (s <= t) & (np.abs(m) < rx_radius_m)
        idx = np.nonzero(hit)[0]
        caps.append((idx, np.full(idx.size, b), length[idx] + s[idx], m[idx]))
        if b == max_refl:
            break
        if history:
            normals[:, b] = nrm
            dirs[:, b] = u
        p = p + t[:, None] * u
        u = u - 2.0 * np.einsum("ij,ij->i", u, nrm)[:, None] * nrm
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        length = length + t
    j, nb, ell, miss = (np.concatenate(c) for c in zip(*caps, strict=True))
    return (j, nb, ell, miss), (normals, dirs)


def _group_captures(j: np.ndarray, nb: np.ndarray, n_rays: int) -> list[np.ndarray]:
    """Captures (sorted by reflection count, then launch index ``j``) grouped into families:
    runs of adjacent launch angles with the same reflection count, a run that wraps around
    phi = 2 pi joined with the run at phi = 0 [family -> capture indices]."""
    new = np.ones(j.size, dtype=bool)
    new[1:] = (nb[1:] != nb[:-1]) | (j[1:] - j[:-1] != 1)
    starts = np.nonzero(new)[0]
    ends = np.append(starts[1:], j.size)
    # join a run that wraps around phi = 2 pi with the run at phi = 0
    runs = [[s, e] for s, e in zip(starts, ends, strict=True)]
    merged = []
    first_of_b = {}
    for s, e in runs:
        b = nb[s]
        if j[s] == 0:
            first_of_b[b] = len(merged)
        merged.append([np.arange(s, e)])
    for k, idx in enumerate(list(merged)):
        s = idx[0][0]
        e = idx[0][-1]
        b = nb[s]
        if j[e] == n_rays - 1 and b in first_of_b and first_of_b[b] != k and merged[first_of_b[b]]:
            tgt = first_of_b[b]
            merged[k] = [np.concatenate([idx[0], merged[tgt][0]])]
            merged[tgt] = []
    groups = [g[0] for g in merged if g]
    return groups


class _FamilyFits(NamedTuple):
    """Per family [f]: the launch angle interpolated to zero miss and the captured one closest
    to it [rad], the tube width J per radian [m], the sign of the miss slope (nan for a
    single-ray family), the number of captured rays, the number of reflections."""

    phi0: np.ndarray
    phi_best: np.ndarray
    jac: np.ndarray
    slope_sign: np.ndarray
    run_len: np.ndarray
    fam_b: np.ndarray


def _fit_families(
    groups: list[np.ndarray],
    j: np.ndarray,
    nb: np.ndarray,
    miss: np.ndarray,
    n_rays: int,
    dphi: float,
    rx_radius_m: float,
) -> _FamilyFits:
    """Each family's central launch angle and tube width from the signed miss distance over
    launch angle (the count of rays in the reception circle bounds the width at caustics);
    launch angles ``dphi`` apart."""
    n_f = len(groups)
    phi0 = np.empty(n_f)
    phi_best = np.empty(n_f)
    jac = np.empty(n_f)
    slope_sign = np.empty(n_f)
    run_len = np.empty(n_f, dtype=int)
    fam_b = np.empty(n_f, dtype=int)
    for f, g in enumerate(groups):
        jj = j[g].astype(float)
        jj = np.where(jj < jj[0], jj + n_rays, jj)  # unwrap
        mm = miss[g]
        fam_b[f] = nb[g[0]]
        run_len[f] = g.size
        phi_best[f] = (jj[np.argmin(np.abs(mm))] + 0.5) * dphi
        if g.size >= 2:
            c, a = np.polyfit(jj - jj[0], mm, 1)
            j0 = jj[0] + (-a / c if c != 0 else 0.5 * (jj[-1] - jj[0]))
            j0 = min(max(j0, jj[0] - 0.5), jj[-1] + 0.5)
            jac_slope = abs(c) / dphi
            jac_count = 2.0 * rx_radius_m / ((g.size + 1) * dphi)
            jac[f] = max(jac_slope, jac_count)
            slope_sign[f] = np.sign(c) if c != 0 else 1.0
        else:
            j0 = jj[0]
            jac[f] = 2.0 * rx_radius_m / (1.5 * dphi)
            slope_sign[f] = np.nan
        phi0[f] = (j0 + 0.5) * dphi
    return _FamilyFits(phi0, phi_best, jac, slope_sign, run_len, fam_b)


class _CentralRays(NamedTuple):
    """Per family [f]: the central ray's launch angle [rad], 2-D length [m] and miss
    distance [m], the normals and directions at its reflections [f, max_refl, 2]."""

    phi0: np.ndarray
    ell_m: np.ndarray
    miss_m: np.ndarray
    normals: np.ndarray
    dirs: np.ndarray


def _retrace_central(
    tunnel: Tunnel, phi0: np.ndarray, phi_best: np.ndarray, fam_b: np.ndarray, max_refl: int, rx_radius_m: float
) -> _CentralRays:
    """Re-trace the central rays (interpolated to zero miss) with their history; where the
    interpolation misses (at caustics m is not linear in phi) keep the closest captured ray."""
    n_f = fam_b.size
    best = None
    for cand in (phi0, phi_best):
        (cj, cb, cell, cmiss), (normals, dirs) = trace_2d(tunnel, cand, max_refl, rx_radius_m, history=True)
        ell_c = np.full(n_f, np.nan)
        miss_c = np.full(n_f, np.inf)
        mine = cb == fam_b[cj]
        for k in np.nonzero(mine)[0]:  # closest approach at the family's order
            f = cj[k]
            if abs(cmiss[k]) < miss_c[f]:
                miss_c[f], ell_c[f] = abs(cmiss[k]), math.hypot(cell[k], cmiss[k])
        if best is None:
            best = [cand.copy(), ell_c, miss_c, normals, dirs]
        else:
            better = miss_c < best[2]
            best[0][better], best[1][better], best[2][better] = cand[better], ell_c[better], miss_c[better]
            best[3][better], best[4][better] = normals[better], dirs[better]
    return _CentralRays(*best)


def sbr_families(tunnel: Tunnel, n_rays: int, max_refl: int, rx_radius_m: float) -> Families:
    """Shooting and bouncing rays in the cross-section (see the module docstring).

    Parameters
    ----------
    tunnel : Tunnel
        The tunnel, either cross-section.
    n_rays : int
        Number of 2-D rays launched uniformly in angle over 2 pi; an integer >= 16.
    max_refl : int
        Largest number of reflections traced [1]; a non-negative integer.
    rx_radius_m : float
        Radius of the reception circle around the receiver [m]; in (0, the receiver's
        distance to the wall).

    Returns
    -------
    Families
        The families found, sorted by reflection count and then 2-D length (families
        whose central ray could not be re-traced are dropped); ``engine`` 'sbr', ``stats``
        with ``n_rays``, ``max_refl``, ``rx_radius_m``, ``n_captures``, ``n_families``,
        ``n_single_ray_families``, ``n_lost_families``, ``max_central_miss_m`` [m].

    Raises
    ------
    ValueError
        When ``n_rays`` is not an integer >= 16, ``max_refl`` is not a non-negative
        integer, or ``rx_radius_m`` is outside (0, the receiver's distance to the wall).
    """
    if not isinstance(n_rays, (int, np.integer)) or n_rays < 16:
        raise ValueError(f"n_rays must be an integer >= 16, got {n_rays!r}")
    if not isinstance(max_refl, (int, np.integer)) or max_refl < 0:
        raise ValueError(f"max_refl must be a non-negative integer, got {max_refl!r}")
    wall = tunnel.wall_distance_m(*tunnel.rx_yz)
    if not 0 < rx_radius_m < wall:
        raise ValueError(
            f"rx_radius_m must be in (0, {wall:.3g}) (the receiver's distance to the wall), got {rx_radius_m!r}"
        )
    dphi = 2.0 * math.pi / n_rays
    phi = (np.arange(n_rays) + 0.5) * dphi
    (j, nb, ell, miss), _ = trace_2d(tunnel, phi, max_refl, rx_radius_m)
    # group captures into families: same reflection count, adjacent launch angles
    o = np.lexsort((j, nb))
    j, nb, ell, miss = j[o], nb[o], ell[o], miss[o]
    groups = _group_captures(j, nb, n_rays)
    phi0, phi_best, jac, slope_sign, run_len, fam_b = _fit_families(groups, j, nb, miss, n_rays, dphi, rx_radius_m)
    n_f = len(groups)
    phi0, ell_f, miss_f, normals, dirs = _retrace_central(tunnel, phi0, phi_best, fam_b, max_refl, rx_radius_m)
    ok = np.isfinite(ell_f)
    # orientation of the tube relative to the line-of-sight family: odd caustic count
    ref = slope_sign[(fam_b == 0) & np.isfinite(slope_sign)]
    ref_sign = ref[0] if ref.size else 1.0
    orient = slope_sign * (-1.0) ** fam_b * ref_sign
    caustic = np.where(orient < 0, math.pi / 2.0, 0.0)
    final = np.empty((n_f, 2))
    rows = np.arange(n_f)
    # direction at the receiver: after fam_b reflections
    last_dir = dirs[rows, np.clip(fam_b - 1, 0, None)]
    last_nrm = normals[rows, np.clip(fam_b - 1, 0, None)]
    refl = last_dir - 2.0 * np.einsum("ij,ij->i", last_dir, last_nrm)[:, None] * last_nrm
    final[:] = np.where((fam_b > 0)[:, None], refl, np.stack([np.cos(phi0), np.sin(phi0)], axis=1))
    spread = np.sqrt(np.where(ok, ell_f, 1.0) / jac)
    sel = np.nonzero(ok)[0]
    srt = sel[np.lexsort((ell_f[sel], fam_b[sel]))]
    stats = {
        "n_rays": int(n_rays),
        "max_refl": int(max_refl),
        "rx_radius_m": float(rx_radius_m),
        "n_captures": int(j.size),
        "n_families": int(srt.size),
        "n_single_ray_families": int(np.sum(run_len[srt] == 1)),
        "n_lost_families": int(np.sum(~ok)),
        "max_central_miss_m": float(np.max(miss_f[srt], initial=0.0)),
    }
    return Families(
        ell_f[srt], fam_b[srt], normals[srt], dirs[srt], final[srt], spread[srt], caustic[srt], "sbr", stats
    )
