"""The wideband receiver over Monte Carlo realizations (docs/model/tunnel.md §3): every
realization's place (each slot's shadowing) and thermal noise at the same positions
synthesized together (:func:`railradio.tunnel.wideband.wideband_delays`), cable ranging with
the receiver's cable model (the installation's stated errors: :class:`CableModelError`), the
+- / which-feed ambiguity resolved from all receivers, and the KF of the head and the tail
receiver on every realization."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from railradio.tunnel.filters import filter_input, head_tail_kf, rigid_train_kf
from railradio.tunnel.geometry import Cable, Tunnel
from railradio.tunnel.wideband import (
    ambiguity_wrong,
    resolve_ambiguity,
    wideband_candidates,
    wideband_delays,
    wideband_view,
)


@dataclass(frozen=True)
class CableModelError:
    """How the receiver's cable model differs from the installed cable (a stated case, never
    drawn from the results; docs/model/tunnel.md §3).

    Parameters
    ----------
    velocity_factor_rel : float
        Relative error of the velocity factor the receiver assumes, (v_model - v) / v [1];
        in (-1, 1).
    feed_delay_max_s : float
        Largest delay error of a feed [s]: each feed's error is uniform in +- this value, one
        draw per feed and realization (any two feeds then differ by at most twice it, the
        way a time-alignment requirement bounds a cell's transmit branches); >= 0.

    Raises
    ------
    ValueError
        When ``velocity_factor_rel`` is not in (-1, 1) or ``feed_delay_max_s`` < 0.
    """

    velocity_factor_rel: float = 0.0
    feed_delay_max_s: float = 0.0

    def __post_init__(self) -> None:
        if not -1.0 < self.velocity_factor_rel < 1.0:
            raise ValueError(f"velocity_factor_rel must be in (-1, 1), got {self.velocity_factor_rel!r}")
        if not self.feed_delay_max_s >= 0:
            raise ValueError(f"feed_delay_max_s must be >= 0, got {self.feed_delay_max_s!r}")

    def receiver_model(self, cable: Cable, n_feeds: int, rng: np.random.Generator | None) -> tuple[float, np.ndarray]:
        """The receiver's velocity factor [1] and assumed extra delay of each feed [feed] [s]
        (``rng`` draws the feeds' errors; may be None when ``feed_delay_max_s`` is 0)."""
        v = cable.velocity_factor * (1.0 + self.velocity_factor_rel)
        if self.feed_delay_max_s > 0:
            return v, rng.uniform(-self.feed_delay_max_s, self.feed_delay_max_s, n_feeds)
        return v, np.zeros(n_feeds)


def wideband_fixes(
    table,
    tunnel: Tunnel,
    cable: Cable,
    offsets_m: np.ndarray,
    x_rx: np.ndarray,
    mm,
    shadows: list,
    rngs: list,
    tones,
    bias_s: float = 0.0,
    models: list | None = None,
) -> list[dict]:
    """Snapshot measurements and fixes of the wideband receiver, one dict per realization.

    Parameters
    ----------
    table : xarray.Dataset
        Tabulated slot-to-receiver channel.
    tunnel : Tunnel
        The tunnel of the table's cross-section.
    cable : Cable
        The installed cable.
    offsets_m : numpy.ndarray
        Each receiver's distance behind the head [m], [receiver].
    x_rx : numpy.ndarray
        True receiver positions [epoch, receiver] [m].
    mm : MeasurementModel
        The receivers' measurement model.
    shadows : list
        Per realization the place's shadowing [slot, x 1 m grid] [dB] (or None).
    rngs : list of numpy.random.Generator
        Per realization the noise stream; receiver j draws from its j-th child.
    tones : tuple of numpy.ndarray
        :func:`railradio.tunnel.wideband.tone_response` of ``table``.
    bias_s : float
        Calibrated delay bias of the peak [s].
    models : list or None
        Per realization the receiver's cable model ``(velocity_factor, feed_delay_s)``
        (:meth:`CableModelError.receiver_model`); None: the installed cable's.

    Returns
    -------
    list of dict
        Per realization: ``tau`` [s], ``fix`` [m], ``scale`` (1), ``ambiguity_wrong``
        [epoch, receiver]; ``candidates`` [epoch, receiver, candidate] [m]; ``head`` [epoch] [m].

    Raises
    ------
    ValueError
        When ``shadows``, ``rngs`` and ``models`` differ in length.
    """
    n_r = len(rngs)
    if len(shadows) != n_r or (models is not None and len(models) != n_r):
        raise ValueError("shadows, rngs and models must hold one entry per realization")
    n_e, k = x_rx.shape
    children = [g.spawn(k) for g in rngs]
    view = wideband_view(table, mm)
    tau = np.empty((n_r, n_e, k))
    for j in range(k):
        tau[:, :, j] = wideband_delays(
            table, tunnel, cable, x_rx[:, j], [c[j] for c in children], view, tones=tones, shadow_db=shadows
        )
    out = []
    for r in range(n_r):
        v, d = models[r] if models is not None else (None, None)
        cand = np.stack(
            [wideband_candidates(tau[r, :, j], tunnel, cable, bias_s, v, d) for j in range(k)], axis=1
        )  # [epoch, receiver, candidate]
        head, fix = resolve_ambiguity(
            cand, offsets_m, cable.feed_spacing_m, (0.0, cable.feed_spacing_m), tunnel.slot_spacing_m
        )
        out.append(
            {
                "tau": tau[r],
                "candidates": cand,
                "head": head,
                "fix": fix,
                "scale": np.ones((n_e, k)),
                "ambiguity_wrong": ambiguity_wrong(cand, fix, x_rx, tunnel.slot_spacing_m),
            }
        )
    return out


def wideband_kf_errors(
    res: list[dict], x_rx: np.ndarray, r0_m2: float, tracking: dict, offsets_m: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """|KF - truth| of the head and the tail receiver and of the rigid-train KF's head
    [realization, epoch] [m]: the same filters as the evaluation run's
    (:func:`railradio.tunnel.filters.head_tail_kf`, :func:`railradio.tunnel.filters.rigid_train_kf`;
    candidates associated with the filter's own prediction, started from the first snapshot
    fixes) on each realization's fixes.

    Parameters
    ----------
    res : list of dict
        :func:`wideband_fixes` of the realizations.
    x_rx : numpy.ndarray
        True receiver positions [epoch, receiver] [m] (scores only).
    r0_m2 : float
        Measurement variance of a fix, from the calibration run [m^2].
    tracking : dict
        ``rate_hz`` [Hz], ``accel_sigma_m_s2`` [m/s^2], ``max_speed_m_s`` [m/s].
    offsets_m : numpy.ndarray
        Each receiver's distance behind the head [m], [receiver] (the rigid train).

    Returns
    -------
    tuple of numpy.ndarray
        ``(err_head, err_tail, err_rigid)``, each [realization, epoch] [m].
    """
    k = x_rx.shape[1]
    ends = (0, k - 1)
    eh, et, er = [], [], []
    for r in res:
        fi = filter_input(r, r0_m2, tracking)
        kf, _, _ = head_tail_kf(fi, ends)
        eh.append(np.abs(kf[:, 0] - x_rx[:, ends[0]]))
        et.append(np.abs(kf[:, 1] - x_rx[:, ends[1]]))
        er.append(np.abs(rigid_train_kf(fi, offsets_m) - x_rx[:, 0]))
    return np.array(eh), np.array(et), np.array(er)
