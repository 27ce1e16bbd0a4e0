"""What each RRH sends in each symbol of a burst by the traffic rule
(:class:`railradio.nr.synthesis.synthesizer.Synthesizer`): which links' data go toward the
train, and each link's amplitude per symbol on its SS-block or data beam, held at the epoch
instant or following the train through the burst (:mod:`railradio.nr.channel.motion`)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from railradio.nr.channel.link import Links


def at_train_mask(data_beam: str, links: Links, serving: NDArray[np.bool_] | None) -> NDArray[np.bool_]:
    """[R] the links whose data go toward the train by the traffic rule ``data_beam``
    (:class:`railradio.nr.synthesis.synthesizer.Synthesizer`; ``serving`` [R]: the serving
    cell's links, or None)."""
    at_train = np.zeros(links.n, dtype=bool)  # links whose data go toward the train
    if data_beam == "train":
        at_train[:] = True
    elif data_beam == "serving" and serving is not None:
        at_train[:] = np.asarray(serving, dtype=bool)
    return at_train


def symbol_gains(
    links: Links,
    draws: list[dict],
    at_train: NDArray[np.bool_],
    sp: dict,
    t_sym: NDArray[np.float64],
    motion,
    f_k: NDArray[np.float64],
) -> tuple[NDArray[np.float32], NDArray[np.complex64] | None]:
    """Each link's amplitude per symbol, × n for the unnormalized IFFT (float32 [R, S]):
    an SS-block symbol on its block's beam, another on the link's data beam; and, under
    ``motion``, the per-symbol geometry phase (complex64 [R, S, n]; else ``None``)."""
    n = f_k.size
    is_ss = sp["block_of"] >= 0
    ss_amp = links.beam_amp[:, np.maximum(sp["block_of"], 0)]  # [R, S]
    data_amp = np.empty(ss_amp.shape)
    for r in range(links.n):  # "none": the data are zero anyway (zero pool)
        data_amp[r] = links.data_amp[r] if at_train[r] else links.beam_amp[r][draws[r]["data_beam"]]
    geo_h = None
    if motion is not None:  # per-symbol geometry at each symbol's receive instant
        ss_amp, geo_h = _motion_geometry(links, draws, at_train, sp, t_sym, motion, f_k)
        data_amp = ss_amp
    g_syms = (np.where(is_ss[None, :], ss_amp, data_amp) * (links.amp * n)[:, None]).astype(
        np.float32
    )  # × n: unnormalized IFFT
    return g_syms, geo_h


def _motion_geometry(
    links: Links,
    draws: list[dict],
    at_train: NDArray[np.bool_],
    sp: dict,
    t_sym: NDArray[np.float64],
    motion,
    f_k: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.complex64]]:
    """Under ``motion``, the links' geometry at each symbol's receive instant (``f_k``: the
    synthesized subcarriers' frequencies, Hz): the beam amplitude of every symbol's beam
    [R, S] and the phase of the delay's and LOS phase's change since the epoch instant,
    e^{j(Δφ - 2π f_k Δτ)} (complex64 [R, S, n])."""
    symbols = sp["symbols"]
    is_ss = sp["block_of"] >= 0
    t_rx = t_sym[None, :] + links.tau_s[:, None]  # [R, S]
    ba_t = motion.beam_amp(t_rx)  # [R, S, B]
    beam = np.empty((links.n, symbols.size), dtype=np.int64)
    for r in range(links.n):
        b_data = (
            np.full(symbols.size, int(np.argmin(np.abs(links.beam_amp[r] - links.data_amp[r]))))
            if at_train[r]
            else draws[r]["data_beam"]
        )
        beam[r] = np.where(is_ss, np.maximum(sp["block_of"], 0), b_data)
    amp = np.take_along_axis(ba_t, beam[:, :, None], axis=2)[:, :, 0]
    d_tau = motion.delay_s(t_rx) - links.tau_s[:, None]  # [R, S]
    geo_h = np.exp(
        1j * (motion.phase_excess_rad(t_rx)[:, :, None] - 2 * np.pi * d_tau[:, :, None] * f_k[None, None, :])
    ).astype(np.complex64)
    return amp, geo_h
