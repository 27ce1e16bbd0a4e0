"""Positioning along the track from LCX slot measurements (source 003 §3-4).

The slots are collinear (one line along the tunnel at a known height and transverse
position), so the position is solved along the track only; the receiver's cross-section
position is known and enters as the cross distance h: d_i^2 = (x - x_i)^2 + h^2.

* :func:`rssi_ls` - RSSI ranging [source 3.1.1] by inverting the model's mean path gain,
  then the source's linearized least squares [source 3.1.2] reduced to the one unknown x.
* :func:`tdoa_gauss_newton` - TDOA range differences [source 3.2.2] solved by weighted
  Gauss-Newton with the correlated TDOA covariance sigma^2 (I + 1 1^T).
* :func:`gdop_source` [source 4.1.1, 2-D in the x-y plane] and :func:`gdop_tdoa_along`
  (the along-track error per unit delay error of the TDOA solution).
* :func:`cep` [source 4.3.2] = 0.59 (sigma_x + sigma_y).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from railradio.constants import SPEED_OF_LIGHT_M_S


def monotone_gain_db(table: xr.Dataset) -> tuple[np.ndarray, np.ndarray]:
    """(offsets, mean path gain in dB made non-increasing with |dx|) for RSSI inversion.

    The local-mean gain of one slot is not strictly monotone (a multiply reflected ray can
    lose less as it grows more grazing); the running minimum is the invertible envelope.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated channel (:func:`railradio.tunnel.channel.tabulate`): ``power_mean``
        (local-mean power gain) [1] over ``offset_m`` [m].

    Returns
    -------
    tuple of numpy.ndarray
        ``(offsets, curve)``, each [offset]: the table's offsets [m] and the running minimum
        of its local-mean gain [dB].
    """
    off = table["offset_m"].values
    g = 10.0 * np.log10(table["power_mean"].values)
    return off, np.minimum.accumulate(g)


def gain_to_offset_m(gain_db, offsets_m: np.ndarray, curve_db: np.ndarray) -> np.ndarray:
    """|dx| at which the monotone curve equals ``gain_db`` (clipped to the table) [m].

    Parameters
    ----------
    gain_db : float or array_like
        Measured path gain of a slot: RSSI minus the cable power at the slot [dB].
    offsets_m : numpy.ndarray
        Increasing offsets of the curve [m], [offset].
    curve_db : numpy.ndarray
        Non-increasing gain at ``offsets_m`` (:func:`monotone_gain_db`) [dB], [offset].

    Returns
    -------
    numpy.ndarray
        Offset |dx| [m], the shape of ``gain_db`` (linear interpolation; gains beyond the
        curve's ends give its first or last offset).
    """
    rev_g, rev_o = curve_db[::-1], offsets_m[::-1]
    # np.interp needs increasing x: the reversed curve is non-decreasing; make it strict
    rev_g = rev_g + np.arange(rev_g.size) * 1e-12
    return np.interp(np.asarray(gain_db, dtype=float), rev_g, rev_o)


def rssi_ls(x_slot_m: np.ndarray, range_m: np.ndarray, h_m: float) -> np.ndarray:
    """Linearized least squares [source 3.1.2] along the track, vectorized over epochs.

    Rows i = 1..n-1 against the reference (column 0, the strongest slot):
    (x - x_i)^2 - (x - x_0)^2 = d_i^2 - d_0^2  ->  2 (x_0 - x_i) x = d_i^2 - d_0^2 - x_i^2 + x_0^2;
    h cancels.  ``x_slot_m``, ``range_m``: [epoch, n] with n >= 2.

    Parameters
    ----------
    x_slot_m : numpy.ndarray
        Slot positions along the track [m], [epoch, n]; column 0 the reference.
    range_m : numpy.ndarray
        Slot-receiver distances d_i (from RSSI ranging) [m], [epoch, n].
    h_m : float
        Cross distance h between slot line and receiver [m]; it cancels (not used).

    Returns
    -------
    numpy.ndarray
        Position x along the track [epoch] [m].

    Raises
    ------
    ValueError
        When ``x_slot_m`` and ``range_m`` differ in shape or are not [epoch, n >= 2].
    """
    xs = np.asarray(x_slot_m, dtype=float)
    d = np.asarray(range_m, dtype=float)
    if xs.shape != d.shape or xs.ndim != 2 or xs.shape[1] < 2:
        raise ValueError("x_slot_m and range_m must have the same shape [epoch, n >= 2]")
    a = 2.0 * (xs[:, :1] - xs[:, 1:])
    b = d[:, 1:] ** 2 - d[:, :1] ** 2 - xs[:, 1:] ** 2 + xs[:, :1] ** 2
    den = np.sum(a * a, axis=1)
    return np.sum(a * b, axis=1) / den


def _rho(x: np.ndarray, xs: np.ndarray, h: float) -> np.ndarray:
    return np.sqrt((x[:, None] - xs) ** 2 + h * h)


def tdoa_gauss_newton(
    x0_m: np.ndarray,
    x_slot_m: np.ndarray,
    range_diff_m: np.ndarray,
    h_m: float,
    sigma_m: float,
    n_iter: int = 20,
    max_step_m: float = 25.0,
):
    """Weighted Gauss-Newton on the TDOA equations [source 3.2.2] along the track.

    ``range_diff_m[:, i-1]`` = c (tau_i - tau_0) for slots i = 1..n-1 against column 0.
    Returns (x [epoch], variance [epoch] from (J^T C^-1 J)^-1).  The TDOA covariance is
    sigma^2 (I + 1 1^T) (every difference shares the reference's error); steps are
    clipped to ``max_step_m`` (far from the slots the equations flatten).

    Parameters
    ----------
    x0_m : numpy.ndarray
        Starting positions along the track (e.g. the RSSI fix) [m], [epoch].
    x_slot_m : numpy.ndarray
        Slot positions along the track [m], [epoch, n]; column 0 the reference.
    range_diff_m : numpy.ndarray
        Range differences c (tau_i - tau_0) [m], [epoch, n - 1].
    h_m : float
        Cross distance h between slot line and receiver [m].
    sigma_m : float
        Standard deviation of each slot's range c tau_i [m]; positive.
    n_iter : int
        Largest number of iterations (they stop when every step is below 1e-6 m).
    max_step_m : float
        Largest step of one iteration [m].

    Returns
    -------
    tuple of numpy.ndarray
        ``(x, var)``, each [epoch]: the position along the track [m] and its variance from
        the geometry at the solution [m^2].

    Raises
    ------
    ValueError
        When ``sigma_m`` is not positive or ``range_diff_m`` is not [epoch, n - 1].
    """
    if sigma_m <= 0:
        raise ValueError("sigma_m must be positive")
    xs = np.asarray(x_slot_m, dtype=float)
    z = np.asarray(range_diff_m, dtype=float)
    n = xs.shape[1] - 1
    if z.shape != (xs.shape[0], n):
        raise ValueError("range_diff_m must be [epoch, n - 1]")
    cinv = (np.eye(n) - np.ones((n, n)) / (n + 1)) / sigma_m**2  # (I + 11^T)^-1 = I - 11^T/(n+1)
    x = np.asarray(x0_m, dtype=float).copy()
    for _ in range(n_iter):
        rho = _rho(x, xs, h_m)
        res = z - (rho[:, 1:] - rho[:, :1])
        dr = (x[:, None] - xs) / rho
        jac = dr[:, 1:] - dr[:, :1]
        info = np.einsum("ei,ij,ej->e", jac, cinv, jac)
        grad = np.einsum("ei,ij,ej->e", jac, cinv, res)
        step = np.clip(grad / np.maximum(info, 1e-300), -max_step_m, max_step_m)
        x = x + step
        if np.all(np.abs(step) < 1e-6):
            break
    rho = _rho(x, xs, h_m)
    dr = (x[:, None] - xs) / rho
    jac = dr[:, 1:] - dr[:, :1]
    info = np.einsum("ei,ij,ej->e", jac, cinv, jac)
    return x, 1.0 / np.maximum(info, 1e-300)


def gdop_source(x_m: np.ndarray, y_m: float, x_slot_m: np.ndarray, y_slot_m: float) -> np.ndarray:
    """GDOP = sqrt(trace((A^T A)^-1)), A = [cos t_i, sin t_i] [source 4.1.1] in the x-y plane.

    t_i is the azimuth from the position to slot i.  With all slots on one line below the
    receiver the matrix is near-singular whenever the slots lie on one side.

    Parameters
    ----------
    x_m : numpy.ndarray
        Receiver positions along the track [m], [epoch].
    y_m : float
        Receiver height above the floor [m].
    x_slot_m : numpy.ndarray
        Slot positions along the track [m], [epoch, n].
    y_slot_m : float
        Slot height above the floor [m].

    Returns
    -------
    numpy.ndarray
        GDOP [epoch] [1].
    """
    dx = np.asarray(x_slot_m, dtype=float) - np.asarray(x_m, dtype=float)[:, None]
    dy = y_slot_m - y_m
    t = np.arctan2(dy, dx)
    a = np.stack([np.cos(t), np.sin(t)], axis=-1)
    ata = np.einsum("eni,enj->eij", a, a)
    det = ata[:, 0, 0] * ata[:, 1, 1] - ata[:, 0, 1] ** 2
    tr = (ata[:, 0, 0] + ata[:, 1, 1]) / np.maximum(det, 1e-300)
    return np.sqrt(tr)


def gdop_tdoa_along(x_m: np.ndarray, x_slot_m: np.ndarray, h_m: float) -> np.ndarray:
    """Along-track standard deviation of the TDOA fix per unit range error c sigma_tau.

    Parameters
    ----------
    x_m : numpy.ndarray
        Positions along the track [m], [epoch].
    x_slot_m : numpy.ndarray
        Slot positions along the track [m], [epoch, n]; column 0 the reference.
    h_m : float
        Cross distance h between slot line and receiver [m].

    Returns
    -------
    numpy.ndarray
        Dilution sigma_x / (c sigma_tau) [epoch] [1].
    """
    x = np.asarray(x_m, dtype=float)
    xs = np.asarray(x_slot_m, dtype=float)
    n = xs.shape[1] - 1
    cinv = np.eye(n) - np.ones((n, n)) / (n + 1)
    dr = (x[:, None] - xs) / _rho(x, xs, h_m)
    jac = dr[:, 1:] - dr[:, :1]
    return 1.0 / np.sqrt(np.einsum("ei,ij,ej->e", jac, cinv, jac))


def cep(sigma_x: np.ndarray, sigma_y: np.ndarray) -> np.ndarray:
    """Circular error probable CEP = 0.59 (sigma_x + sigma_y) [source 4.3.2].

    Parameters
    ----------
    sigma_x : float or array_like
        Standard deviation of the position error along x [m].
    sigma_y : float or array_like
        Standard deviation of the position error along y [m].

    Returns
    -------
    numpy.ndarray
        CEP [m], the broadcast shape of ``sigma_x`` and ``sigma_y``.
    """
    return 0.59 * (np.asarray(sigma_x) + np.asarray(sigma_y))


def range_diff_from_delays(delay_s: np.ndarray) -> np.ndarray:
    """c (tau_i - tau_0) for columns 1..n-1 against column 0 [m].

    Parameters
    ----------
    delay_s : numpy.ndarray
        Measured slot delays tau [s], [epoch, n]; column 0 the reference.

    Returns
    -------
    numpy.ndarray
        Range differences [m], [epoch, n - 1].
    """
    d = np.asarray(delay_s, dtype=float)
    return SPEED_OF_LIGHT_M_S * (d[:, 1:] - d[:, :1])
