"""Bursts of several amplitude variants of one scenario from one synthesis per epoch.

Map cells and sensitivity cases that differ from each other only in what each RRH sends
with which amplitude — the Tx elements M_T (the beams' gains), the data's beam and load, the
Tx power — share the channel, the draws and the noise of every epoch: :class:`VariantSynthesis`
synthesizes each link's unit parts once (:mod:`railradio.nr.synthesis.parts`,
:mod:`railradio.nr.synthesis.edge_parts`) and returns each variant's burst on the lag grid as
:class:`railradio.nr.engine.frontend.SpectralSynthesis` of that variant returns it (equal to
float32 rounding, ``tests/nr/test_variants.py``). Receiver settings may differ freely: they
read the bursts, and variants with the same amplitudes and front end read one burst (the
map's cells that change only the receiver: its window, template or selection).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
import xarray as xr

from railradio.nr.engine.epochs import PROGRESS_EVERY_S, _Progress, simulate_epochs
from railradio.nr.engine.estimates_dataset import EpochRecord, estimates_dataset
from railradio.nr.engine.estimator import SharedEstimator
from railradio.nr.engine.frontend import SpectralSynthesis
from railradio.nr.engine.simulate import KEY_EPOCH, KEY_POOL, Burst, Scenario, scenario_from_config
from railradio.nr.receiver.frontend import front_end
from railradio.nr.synthesis.beams import at_train_mask, symbol_gains
from railradio.nr.synthesis.edge_parts import EdgeParts
from railradio.nr.synthesis.parts import PartsSynthesizer, weigh
from railradio.nr.waveform.ssb import qpsk_pool
from railradio.rng import make_rng

AMPLITUDE_FIELDS = ("rrh_array", "data_beam", "load", "radio.tx_power_dbm")
"""The scenario fields an amplitude variant may change (besides the receivers')."""

RECEIVER_FIELDS = ("receiver", "extra_receivers", "detector", "pfa", "cell_search", "search_decimation")
"""The receivers' fields: they read the bursts and may differ between variants."""


def _same(a, b) -> bool:
    """Whether two settings are equal: dataclasses and plain objects field by field, arrays
    element by element."""
    if type(a) is not type(b):
        return False
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and bool(np.array_equal(a, b))
    if dataclasses.is_dataclass(a):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if hasattr(a, "__dict__") and not isinstance(a, type):
        return _same(vars(a), vars(b))
    return bool(a == b)


def _channel(scn: Scenario) -> dict:
    """The settings variants share, by field: all of ``scn``'s but the amplitudes and the
    receivers, and of the receiver those that shape the burst (rate, SS-block pattern)."""
    out = {f.name: getattr(scn, f.name) for f in dataclasses.fields(Scenario) if f.name not in RECEIVER_FIELDS}
    out["rrh_array"] = dataclasses.replace(scn.rrh_array, n_elements=0)
    out["radio"] = dataclasses.replace(scn.radio, tx_power_dbm=0.0)
    del out["data_beam"], out["load"]
    rx = scn.receiver
    out["receiver"] = (rx.decimation, rx.ssb_pattern, rx.n_blocks)
    return out


def check_variants(scns: Sequence[Scenario]) -> None:
    """Raise unless the scenarios differ only in :data:`AMPLITUDE_FIELDS` and the receivers'
    settings, and run the study's synthesis path (band edges and the exact spill).

    Parameters
    ----------
    scns : sequence of Scenario
        The variants.

    Raises
    ------
    ValueError
        When ``scns`` is empty, two scenarios differ in another field (named), or the path
        is not the study's.
    """
    if not scns:
        raise ValueError("scns must hold at least one Scenario")
    base = _channel(scns[0])
    for i, s in enumerate(scns[1:], start=1):
        other = _channel(s)
        diff = [k for k in base if not _same(base[k], other[k])]
        if diff:
            raise ValueError(f"scns[{i}] differs from scns[0] beyond the amplitudes and receivers: {diff}")
    s0 = scns[0]
    d_s = s0.receiver.decimation if s0.synthesis_decimation is None else s0.synthesis_decimation
    if not (s0.exact_spill and s0.band_edges and d_s < s0.receiver.decimation):
        raise ValueError("the variants need the study's path: exact_spill, band_edges and a band synthesis")


class VariantSynthesis:
    """Each variant's received burst of an epoch on the lag grid, from one synthesis of the
    links' unit parts (see the module's description).

    Parameters
    ----------
    scns : sequence of Scenario
        The variants (:func:`check_variants`).
    seed : int
        The config seed.
    key : tuple of int
        The realization's spawn key (every variant's: they share the draws).

    Raises
    ------
    ValueError
        From :func:`check_variants`.
    """

    def __init__(self, scns: Sequence[Scenario], seed: int, key: tuple[int, ...]):
        check_variants(scns)
        self.scns = list(scns)
        self.seed, self.key = seed, key
        self.own = [SpectralSynthesis(s, seed, key) for s in self.scns]  # truth, network, front end
        for o in self.own:
            o.edges = None  # the parts give them
        ref = self.own[0]
        syn0 = ref.syn
        pool = qpsk_pool(make_rng(seed, key + (KEY_POOL,)), self.scns[0].pool_size)
        self.parts = PartsSynthesizer(
            syn0.cfg,
            syn0.profile,
            pool,
            syn0.n_sinusoids,
            syn0.full_channel_range_m,
            data_beam="random",
            exact_spill=True,
        )
        self.edges = EdgeParts(self.parts, pool, self.scns[0].receiver.decimation)

    def __call__(self, epoch: int) -> list[Burst]:
        """Every variant's burst of ``epoch`` (``Burst.z`` at F_s/D_c of its receiver) and truth.

        Parameters
        ----------
        epoch : int
            Epoch index.

        Returns
        -------
        list of Burst
            One per variant, in the order of ``scns``.

        Raises
        ------
        ValueError
            When the variants' links at the epoch differ beyond their amplitudes.
        """
        truths = [o.advance(epoch) for o in self.own]
        lb0 = truths[0][3]
        links = lb0.links
        for _, _, _, lb, _ in truths[1:]:
            if not (np.array_equal(lb.links.tau_s, links.tau_s) and np.array_equal(lb.links.n_id1, links.n_id1)):
                raise ValueError(f"epoch {epoch}: the variants' links differ beyond their amplitudes")
        t = epoch * self.scns[0].trajectory.dt_s
        rng = make_rng(self.seed, self.key + (KEY_EPOCH, int(epoch)))
        draws = self.parts.draws(links, rng)
        parts = self.parts.parts(links, rng, draws, t0_s=t, d2d_m=lb0.link_d2d_m)
        edges, m_full = self.edges.parts(links, draws, t, lb0.link_d2d_m, gains=self.parts.kept_gains)
        sp = self.parts.span(float(np.max(links.tau_s)) if links.n else 0.0)
        n = self.parts.cfg.num.n_fft
        t_sym = (self.parts.cfg.num.symbol_start(sp["symbols"]) + sp["cps"] + n / 2) / (
            self.parts.cfg.num.sample_rate_hz
        ) + t
        out = []
        made: dict[tuple, np.ndarray] = {}  # the bursts by amplitudes and front end
        for scn, o, (x, v, a, lb, serving) in zip(self.scns, self.own, truths, strict=True):
            link_rrh = lb.rrh if lb.link_rrh is None else lb.link_rrh
            serv = np.asarray(link_rrh) == serving
            w = self.weights(scn, lb.links, draws, serv, sp, t_sym)
            seen = (w.tobytes(), o.down, o.up)
            if seen not in made:  # a variant differing from an earlier one only in its receivers reads its burst
                z = weigh(parts, w)
                spec = self.edges.weigh(edges, m_full, w)
                made[seen] = front_end(z, o.down, o.up, spec)
                made[seen].flags.writeable = False  # the receivers read a burst, never write it
            out.append(Burst(made[seen], parts.s_min, x, v, a, lb, serving))
        return out

    def weights(self, scn: Scenario, links, draws, serving, sp, t_sym) -> np.ndarray:
        """A variant's amplitude of each link's parts per symbol, float32 [R, 2, S]: the
        overlay's g_{r,s} and the data's g_{r,s}·d_{r,s} (d: the symbol carries data by the
        variant's traffic rule, :class:`railradio.nr.synthesis.synthesizer.Synthesizer`)."""
        at_train = at_train_mask(scn.data_beam, links, serving)
        g, _ = symbol_gains(links, draws, at_train, sp, t_sym, None, self.parts.f_k)
        data = np.zeros(g.shape, dtype=bool)
        if scn.data_beam != "none":
            for r in range(links.n):
                data[r] = True if at_train[r] else draws[r]["busy_u"] < scn.load
        return np.ascontiguousarray(np.stack([g, g * data], axis=1), dtype=np.float32)


MIN_GROUP = 4
"""Fewest variants run together by :func:`variant_groups`: the parts pay from 3.2 variants
(``bench_nr``'s ``variants.break_even``, 2026-12-06), so a group of four or more is cheaper
than its variants' own syntheses."""


def _partition(scns: dict[str, Scenario]) -> list[list[str]]:
    """Names of ``scns`` in groups of amplitude variants (:func:`check_variants`), in their
    order, first come first grouped."""
    groups: list[list[str]] = []
    for name, scn in scns.items():
        for g in groups:
            try:
                check_variants([scns[g[0]], scn])
            except ValueError:
                continue
            g.append(name)
            break
        else:
            groups.append([name])
    return groups


def variant_groups(configs: dict[str, dict], min_group: int = MIN_GROUP) -> list[list[str]]:
    """Split named nr configs into groups of amplitude variants (:func:`check_variants`), each
    group in the configs' order, first come first grouped; configs in groups smaller than
    ``min_group`` are left out (they run on their own).

    Parameters
    ----------
    configs : dict of str to dict
        Name -> an ``nr`` config section (as :func:`railradio.nr.engine.simulate.scenario_from_config` takes it).
    min_group : int
        The smallest group returned.

    Returns
    -------
    list of list of str
        The groups' names.
    """
    groups = _partition({name: scenario_from_config(cfg) for name, cfg in configs.items()})
    return [g for g in groups if len(g) >= min_group]


def simulate_cells(
    scns: dict[str, Scenario], epochs: np.ndarray, seed: int, key: tuple[int, ...], min_group: int = MIN_GROUP
) -> dict[str, xr.Dataset]:
    """The estimates of several scenarios on the same epochs and key: each group of at least
    ``min_group`` amplitude variants from one synthesis per epoch
    (:func:`simulate_variant_epochs`), any other scenario on its own
    (:func:`railradio.nr.engine.epochs.simulate_epochs`).

    Parameters
    ----------
    scns : dict of str to Scenario
        Name -> scenario.
    epochs : array_like of int
        Epoch indices, strictly increasing.
    seed, key : int, tuple of int
        Config seed and the realization's spawn key.
    min_group : int
        The fewest variants synthesized together.

    Returns
    -------
    dict of str to xarray.Dataset
        Name -> its estimates, in the order of ``scns``.

    Raises
    ------
    ValueError
        When ``epochs`` is not strictly increasing.
    """
    out: dict[str, xr.Dataset] = {}
    for group in _partition(scns):
        if len(group) >= min_group:
            out.update(zip(group, simulate_variant_epochs([scns[g] for g in group], epochs, seed, key), strict=True))
        else:
            out.update({g: simulate_epochs(scns[g], epochs, seed, key) for g in group})
    return {name: out[name] for name in scns}


def simulate_variant_epochs(
    scns: Sequence[Scenario],
    epochs: np.ndarray,
    seed: int,
    key: tuple[int, ...],
    progress_every_s: float = PROGRESS_EVERY_S,
) -> list[xr.Dataset]:
    """:func:`railradio.nr.engine.epochs.simulate_epochs` of each variant, from one synthesis
    per epoch (:class:`VariantSynthesis`), each variant with its own receivers and state.

    Parameters
    ----------
    scns : sequence of Scenario
        The variants (:func:`check_variants`).
    epochs : array_like of int
        Epoch indices, strictly increasing.
    seed, key : int, tuple of int
        Config seed and the realization's spawn key.
    progress_every_s : float
        Longest wall time between two progress lines, s.

    Returns
    -------
    list of xarray.Dataset
        One estimates dataset per variant, as ``simulate_epochs`` returns it.

    Raises
    ------
    ValueError
        When ``epochs`` is not strictly increasing, the variants' receivers restart at
        different epochs, or from :func:`check_variants`.
    """
    epochs = np.asarray(epochs, dtype=np.int64)
    if np.any(np.diff(epochs) <= 0):
        raise ValueError("epochs must be strictly increasing")
    vs = VariantSynthesis(scns, seed, key)
    ests = [SharedEstimator(s, on_lag_grid=True) for s in vs.scns]
    recs = [
        EpochRecord.empty(len(est.receivers), epochs.size, min(s.cell_search.n_neighbours, s.deployment.n_rrh))
        for s, est in zip(vs.scns, ests, strict=True)
    ]
    progress, bursts = _Progress(epochs.size, progress_every_s), 0
    for i, e in enumerate(epochs):
        starts = {est.start(int(e)) for est in ests}
        if len(starts) > 1:
            raise ValueError(f"epoch {e}: the variants' receivers restart at different epochs {sorted(starts)}")
        for w in range(starts.pop(), int(e)):  # warm-up: the cell searches' state at e
            for est, b in zip(ests, vs(w), strict=True):
                est(w, b.z, b.s_min, report=False)
            bursts += 1
        for s, est, rec, b in zip(vs.scns, ests, recs, vs(int(e)), strict=True):
            rec.record(i, int(e), b, est(int(e), b.z, b.s_min), s.deployment)
        bursts += 1
        progress(i + 1, bursts)
    return [
        estimates_dataset(s, epochs, [name for name, _, _ in est.receivers], rec)
        for s, est, rec in zip(vs.scns, ests, recs, strict=True)
    ]
