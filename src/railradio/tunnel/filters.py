"""The trackers of one train crossing on its snapshot fixes: KF on the head and on the tail
receiver, rigid-train KF on all receivers, particle filter on head and tail; every filter
starts from the first snapshot fix with its variance, not from the truth."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from railradio.tunnel.tracking import kf_track, pf_track


class FilterInput(NamedTuple):
    """What every filter of :func:`railradio.tunnel.simulate.run_train` reads: the measurements
    [epoch, receiver, candidate], their variances R_t [epoch, receiver] [m^2], the epoch [s],
    the acceleration sigma [m/s^2], the maximum speed [m/s], and the first snapshot fix
    [receiver] [m] with its variance [m^2] (every filter starts from it, not from the truth)."""

    meas: np.ndarray
    r_t: np.ndarray
    dt: float
    q: float
    vmax: float
    z0: np.ndarray
    p0: np.ndarray


def head_tail_kf(fi: FilterInput, ends: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """KF on the head and on the tail receiver: positions, variances, NIS [epoch, 2].

    Parameters
    ----------
    fi : FilterInput
        Measurements, their variances, the motion model and the first snapshot fixes.
    ends : tuple of int
        Receiver indices (columns of ``fi.meas``) of the head and the tail receiver.

    Returns
    -------
    tuple of numpy.ndarray
        ``(kf, kf_var, nis)``, each [epoch, 2] (head receiver, tail receiver): the filtered
        receiver positions [m], their variances [m^2] and the normalized innovation squared
        [1] (NaN at epochs without an update).

    Raises
    ------
    ValueError
        When a measurement variance, the epoch or the acceleration sigma is not positive
        (:func:`~railradio.tunnel.tracking.kf_track`).
    """
    n_t = fi.meas.shape[0]
    kf = np.empty((n_t, 2))
    kf_var = np.empty((n_t, 2))
    nis = np.empty((n_t, 2))
    for c, j in enumerate(ends):
        kf[:, c], _, kf_var[:, c], nis[:, c] = kf_track(
            fi.meas[:, j : j + 1],
            fi.r_t[:, j : j + 1],
            fi.dt,
            fi.q,
            (fi.z0[j], 0.0),
            (fi.p0[j], fi.vmax**2),
            start_at_first=True,
        )
    return kf, kf_var, nis


def rigid_train_kf(fi: FilterInput, offs: np.ndarray) -> np.ndarray:
    """Rigid-train KF on all receivers (``offs`` [m] behind the head): the head position [epoch] [m].

    Parameters
    ----------
    fi : FilterInput
        Measurements, their variances, the motion model and the first snapshot fixes; the
        filter starts from the precision-weighted head of all receivers' first fixes.
    offs : numpy.ndarray
        Each receiver's distance behind the head [m], [receiver].

    Returns
    -------
    numpy.ndarray
        The filtered head position [epoch] [m].

    Raises
    ------
    ValueError
        When ``offs`` has not one entry per receiver, or a measurement variance, the epoch
        or the acceleration sigma is not positive (:func:`~railradio.tunnel.tracking.kf_track`).
    """
    w0 = 1.0 / fi.p0  # rigid train: the precision-weighted head from all receivers' first fixes
    rigid, _, rigid_var, _ = kf_track(
        fi.meas,
        fi.r_t,
        fi.dt,
        fi.q,
        (float(np.sum(w0 * (fi.z0 + offs)) / np.sum(w0)), 0.0),
        (float(1.0 / np.sum(w0)), fi.vmax**2),
        offsets_m=offs,
        start_at_first=True,
    )
    return rigid


def head_tail_pf(fi: FilterInput, ends: tuple[int, int], n_particles: int, rng_pf: np.random.Generator) -> np.ndarray:
    """Particle filter on the head and on the tail receiver, one ``rng_pf`` in turn [epoch, 2].

    Parameters
    ----------
    fi : FilterInput
        Measurements, their variances, the motion model and the first snapshot fixes.
    ends : tuple of int
        Receiver indices (columns of ``fi.meas``) of the head and the tail receiver.
    n_particles : int
        Particles of each filter; >= 10.
    rng_pf : numpy.random.Generator
        Random stream of both filters (the head receiver's first).

    Returns
    -------
    numpy.ndarray
        The filtered positions of the head and the tail receiver [epoch, 2] [m].

    Raises
    ------
    ValueError
        When ``n_particles`` < 10, or the epoch or the acceleration sigma is not positive.
    """
    pf = np.empty((fi.meas.shape[0], 2))
    for c, j in enumerate(ends):
        pf[:, c], _ = pf_track(
            fi.meas[:, j],
            fi.r_t[:, j],
            fi.dt,
            fi.q,
            (fi.z0[j], 0.0),
            (fi.p0[j], fi.vmax**2),
            n_particles,
            rng_pf,
            start_at_first=True,
        )
    return pf


@dataclass(frozen=True)
class Tracks:
    """The evaluation run's tracks [m]: ``kf``, ``kf_var`` [m^2], ``nis``, ``pf`` [epoch, 2]
    (head and tail receiver), ``rigid`` [epoch] (the rigid-train KF's head)."""

    kf: np.ndarray
    kf_var: np.ndarray
    nis: np.ndarray
    rigid: np.ndarray
    pf: np.ndarray


def filter_input(res: dict, r0: float, tracking: dict) -> FilterInput:
    """What every filter reads from snapshot fixes ``res`` (``fix``, ``scale`` [epoch, receiver],
    ``candidates`` [epoch, receiver, candidate] or None): R_t = r0 s_t^2 [m^2], the motion
    model of ``tracking`` (``rate_hz`` [Hz], ``accel_sigma_m_s2`` [m/s^2], ``max_speed_m_s``
    [m/s]), and the start: the first snapshot fix with its variance (not the truth)."""
    meas = res["candidates"] if res["candidates"] is not None else res["fix"][..., None]
    r_t = r0 * res["scale"] ** 2
    return FilterInput(
        meas,
        r_t,
        1.0 / tracking["rate_hz"],
        tracking["accel_sigma_m_s2"],
        tracking["max_speed_m_s"],
        res["fix"][0],
        r_t[0],
    )


def track_fixes(res: dict, r0: float, tracking: dict, offsets_m: np.ndarray, rng_pf: np.random.Generator) -> Tracks:
    """KF on the head and on the tail receiver, rigid-train KF on all receivers (``offsets_m``
    behind the head), PF on head and tail, all from the snapshot fixes ``res`` of
    :func:`railradio.tunnel.simulate.snapshot_fixes` with R_t = r0 s_t^2.

    Parameters
    ----------
    res : dict
        Snapshot fixes of :func:`railradio.tunnel.simulate.snapshot_fixes`: ``fix``
        [epoch, receiver] [m], ``scale`` (each fix's relative standard deviation s_t)
        [epoch, receiver] [1] and ``candidates`` [epoch, receiver, candidate] [m] or None.
    r0 : float
        Measurement variance per unit ``scale`` squared, from the calibration run [m^2].
    tracking : dict
        The ``tracking`` section of the configuration: ``rate_hz`` [Hz],
        ``accel_sigma_m_s2`` [m/s^2], ``max_speed_m_s`` [m/s], ``n_particles``.
    offsets_m : numpy.ndarray
        Each receiver's distance behind the head [m], [receiver].
    rng_pf : numpy.random.Generator
        Random stream of the particle filters.

    Returns
    -------
    Tracks
        ``kf``, ``kf_var``, ``nis`` and ``pf`` [epoch, 2] of the head and the tail receiver,
        ``rigid`` [epoch] (positions [m], variances [m^2], NIS [1]).

    Raises
    ------
    ValueError
        When a measurement variance is not positive or the tracking parameters are invalid.
    """
    fi = filter_input(res, r0, tracking)
    ends = (0, res["fix"].shape[1] - 1)
    kf, kf_var, nis = head_tail_kf(fi, ends)
    rigid = rigid_train_kf(fi, offsets_m)
    return Tracks(kf, kf_var, nis, rigid, head_tail_pf(fi, ends, tracking["n_particles"], rng_pf))
