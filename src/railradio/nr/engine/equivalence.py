"""The burst engine (:class:`railradio.nr.engine.SpectralSynthesis` and
:class:`railradio.nr.engine.SharedEstimator`) against the study's path
(:class:`railradio.nr.engine.simulate.Synthesis` and :class:`~railradio.nr.engine.simulate.Estimator`) on
the same draws: which decisions the change of arithmetic moves (float32 rounding: the front
end in one spectral pass, the PSS + SSS correlation as the sum of its parts, the
refinement's grid samples read from the lag grid).

Both paths run the same consecutive epochs of one realization from the same state, each
with its own cell search, so a changed neighbour list counts and carries on. Counted per
receiver over the (epoch, candidate) pairs both lists share: detected-block counts, TOAs
(full-rate lags), AODs (more than 1 µrad apart), and per epoch the selected cell of each
selection rule.

    python -m railradio.nr.engine.equivalence --config config/config.yaml --first 1500 --epochs 300 --out eq.json

Across a change of the engine (:func:`engine_decisions`, :func:`compare_decisions`): the
engine's decisions on the same epochs dumped by each version of the code, then counted as
above (the older version runs this file with its own ``railradio`` on the path):

    PYTHONPATH=<old>/src python src/railradio/nr/engine/equivalence.py --dump old.pkl
    python -m railradio.nr.engine.equivalence --dump new.pkl
    python -m railradio.nr.engine.equivalence --against old.pkl new.pkl --out eq.json

The reproduction map's cells that share one synthesis per epoch, each synthesized on its
own against :class:`railradio.nr.engine.variants.VariantSynthesis` (:func:`compare_variants`):
``python -m railradio.nr.study.map_equivalence``.
"""

from __future__ import annotations

import argparse
import json
import pickle
import time
from types import SimpleNamespace

import numpy as np
import yaml

from railradio.nr.engine.estimator import SharedEstimator
from railradio.nr.engine.frontend import SpectralSynthesis
from railradio.nr.engine.simulate import Estimator, Synthesis, scenario_from_config
from railradio.nr.waveform.numerology import SAMPLE_RATE_HZ
from railradio.rng import spawn_key

AOD_TOL_RAD = 1e-6
"""AODs further apart than this count as changed (the weights' float32 rounding moves an AOD
by ~1e-7 rad)."""


SELECTIONS = ("ss_rsrp", "peak", "best_score")
"""The cell-selection rules whose picks are compared."""


def _selected(m, j: int) -> dict[str, int]:
    """The RRH each selection rule picks for receiver ``j`` (-1: none)."""
    rows = {"ss_rsrp": m.ss_rsrp_db, "peak": m.peak[j], "best_score": m.best_score[j]}
    return {r: int(m.cand[np.nanargmax(v)]) if np.isfinite(v).any() else -1 for r, v in rows.items()}


def _consecutive(epochs) -> np.ndarray:
    """``epochs`` as int64, checked consecutive (ValueError otherwise)."""
    epochs = np.asarray(epochs, dtype=np.int64)
    if np.any(np.diff(epochs) != 1):
        raise ValueError("epochs must be consecutive")
    return epochs


def _tally(names) -> tuple[dict, dict]:
    """Empty counts per receiver name: of the shared pairs and of the selections."""
    kinds = ("pairs", "detections_changed", "toa_changed", "aod_changed")
    return {n: dict.fromkeys(kinds, 0) for n in names}, {n: dict.fromkeys(SELECTIONS, 0) for n in names}


def compare(scn, seed: int, key: tuple[int, ...], epochs: np.ndarray) -> dict:
    """Run both estimators on the bursts of ``epochs`` (consecutive) and count what differs.

    Parameters
    ----------
    scn : railradio.nr.engine.simulate.Scenario
        The scenario.
    seed, key : int, tuple of int
        The config seed and the realization's spawn key.
    epochs : numpy.ndarray of int
        Consecutive epoch indices.

    Returns
    -------
    dict
        ``epochs``; ``lists_changed`` (epochs whose neighbour lists differ); per receiver name,
        over the shared pairs: ``pairs``, ``detections_changed``, ``toa_changed``,
        ``aod_changed`` and ``selection_changed`` per rule (shares of epochs); ``ms_per_epoch``
        of each path, synthesis and receivers (process time).

    Raises
    ------
    ValueError
        When ``epochs`` are not consecutive.
    """
    epochs = _consecutive(epochs)
    syn, spectral = Synthesis(scn, seed, key), SpectralSynthesis(scn, seed, key)
    old, new = Estimator(scn), SharedEstimator(scn, on_lag_grid=True)
    names = [n for n, _, _ in old.receivers]
    old.start(int(epochs[0]))
    new.start(int(epochs[0]))
    count, sel = _tally(names)
    lists, cost = 0, {"study": 0.0, "engine": 0.0}
    for e in epochs:
        t0 = time.process_time()
        b = syn(int(e))
        mo = old(int(e), b.z, b.s_min)
        t1 = time.process_time()
        b = spectral(int(e))
        mn = new(int(e), b.z, b.s_min)
        cost["study"] += t1 - t0
        cost["engine"] += time.process_time() - t1
        lists += _count(mo, mn, names, count, sel)
    return _shares(epochs.size, lists, names, count, sel) | {
        "ms_per_epoch": {k: 1e3 * v / epochs.size for k, v in cost.items()}
    }


DECISION_FIELDS = ("cand", "n_detected", "toa_s", "aod_rad", "ss_rsrp_db", "peak", "best_score")
"""What :func:`engine_decisions` keeps of each epoch's measurements."""


def engine_decisions(scn, seed: int, key: tuple[int, ...], epochs: np.ndarray) -> dict:
    """The burst engine's measurements of ``epochs`` (consecutive, one cell search from the
    first), as plain arrays: what :func:`compare_decisions` counts between two versions.

    Parameters
    ----------
    scn : railradio.nr.engine.simulate.Scenario
        The scenario.
    seed, key : int, tuple of int
        The config seed and the realization's spawn key.
    epochs : numpy.ndarray of int
        Consecutive epoch indices.

    Returns
    -------
    dict
        ``epochs``, ``names`` (the receivers), ``run`` (the seed, the spawn key and the
        scenario, as text: what must match to compare), ``decisions`` (per epoch, a dict of
        :data:`DECISION_FIELDS`) and ``ms_per_epoch`` (process time).

    Raises
    ------
    ValueError
        When ``epochs`` are not consecutive.
    """
    epochs = _consecutive(epochs)
    syn, est = SpectralSynthesis(scn, seed, key), SharedEstimator(scn, on_lag_grid=True)
    est.start(int(epochs[0]))
    out, t0 = [], time.process_time()
    for e in epochs:
        b = syn(int(e))
        m = est(int(e), b.z, b.s_min)
        out.append({f: np.array(getattr(m, f)) for f in DECISION_FIELDS})
    cost = 1e3 * (time.process_time() - t0) / epochs.size
    names = [n for n, _, _ in est.receivers]
    run = {"seed": int(seed), "key": [int(k) for k in key], "scenario": repr(scn)}
    return {"epochs": epochs, "names": names, "run": run, "decisions": out, "ms_per_epoch": cost}


def compare_decisions(old: dict, new: dict) -> dict:
    """What differs between two :func:`engine_decisions` of the same epochs, counted as
    :func:`compare` counts it.

    Parameters
    ----------
    old, new : dict
        :func:`engine_decisions` of two versions of the engine.

    Returns
    -------
    dict
        As :func:`compare`, with ``ms_per_epoch`` of each version.

    Raises
    ------
    ValueError
        When the two ran other epochs, receivers, seeds, realizations or scenarios.
    """
    if not np.array_equal(old["epochs"], new["epochs"]) or list(old["names"]) != list(new["names"]):
        raise ValueError("old and new must hold the same epochs and receivers")
    if old["run"] != new["run"]:
        raise ValueError("old and new must come from the same seed, realization and scenario")
    names = list(old["names"])
    count, sel = _tally(names)
    lists = 0
    for do, dn in zip(old["decisions"], new["decisions"], strict=True):
        lists += _count(SimpleNamespace(**do), SimpleNamespace(**dn), names, count, sel)
    shares = _shares(len(old["epochs"]), lists, names, count, sel)
    return shares | {"ms_per_epoch": {"old": old["ms_per_epoch"], "new": new["ms_per_epoch"]}}


def _count(mo, mn, names, count, sel) -> int:
    """Add what differs between two estimators' measurements of one epoch to ``count`` and
    ``sel``; 1 when their neighbour lists differ."""
    common = np.intersect1d(mo.cand, mn.cand)
    io = np.array([int(np.flatnonzero(mo.cand == c)[0]) for c in common], dtype=np.int64)
    in_ = np.array([int(np.flatnonzero(mn.cand == c)[0]) for c in common], dtype=np.int64)
    for j, n in enumerate(names):
        c = count[n]
        c["pairs"] += common.size
        c["detections_changed"] += int(np.sum(mo.n_detected[j, io] != mn.n_detected[j, in_]))
        to, tn = mo.toa_s[j, io] * SAMPLE_RATE_HZ, mn.toa_s[j, in_] * SAMPLE_RATE_HZ
        c["toa_changed"] += int(np.sum(~((to == tn) | (np.isnan(to) & np.isnan(tn)))))
        ao, an = mo.aod_rad[j, io], mn.aod_rad[j, in_]
        c["aod_changed"] += int(np.sum(~((np.abs(ao - an) <= AOD_TOL_RAD) | (np.isnan(ao) & np.isnan(an)))))
        po, pn = _selected(mo, j), _selected(mn, j)
        for r in sel[n]:
            sel[n][r] += int(po[r] != pn[r])
    return int(not np.array_equal(mo.cand, mn.cand))


def _shares(n_e, lists, names, count, sel) -> dict:
    """The counts as shares: of the shared pairs, and of the epochs for the selections."""
    out = {"epochs": int(n_e), "lists_changed": lists / n_e}
    for n in names:
        p = max(count[n]["pairs"], 1)
        out[n] = {"pairs": count[n]["pairs"]} | {k: v / p for k, v in count[n].items() if k != "pairs"}
        out[n]["selection_changed"] = {r: v / n_e for r, v in sel[n].items()}
    return out


def compare_variants(scns, seed: int, key: tuple[int, ...], epochs: np.ndarray) -> dict:
    """Each amplitude variant's own synthesis (:class:`SpectralSynthesis`) against the
    variants' one synthesis (:class:`railradio.nr.engine.variants.VariantSynthesis`), each
    with its own receivers (:class:`SharedEstimator`), on consecutive ``epochs``: what
    differs, per variant, counted as :func:`compare` counts it.

    Parameters
    ----------
    scns : sequence of Scenario
        The variants (:func:`railradio.nr.engine.variants.check_variants`).
    seed, key : int, tuple of int
        The config seed and the realization's spawn key.
    epochs : numpy.ndarray of int
        Consecutive epoch indices.

    Returns
    -------
    dict
        ``epochs``; per variant index (str) the shares of :func:`compare`; ``ms_per_epoch``
        of each path (all variants, synthesis and receivers, process time).

    Raises
    ------
    ValueError
        When ``epochs`` are not consecutive, or from ``check_variants``.
    """
    from railradio.nr.engine.variants import VariantSynthesis

    epochs = _consecutive(epochs)
    vs = VariantSynthesis(scns, seed, key)
    own = [SpectralSynthesis(s, seed, key) for s in scns]
    old = [SharedEstimator(s, on_lag_grid=True) for s in scns]
    new = [SharedEstimator(s, on_lag_grid=True) for s in scns]
    for est in old + new:
        est.start(int(epochs[0]))
    names = [[n for n, _, _ in est.receivers] for est in old]
    tallies = [_tally(nm) for nm in names]
    count, sel = [t[0] for t in tallies], [t[1] for t in tallies]
    lists, cost = [0] * len(scns), {"own": 0.0, "variants": 0.0}
    for e in epochs:
        t0 = time.process_time()
        mo = [est(int(e), b.z, b.s_min) for est, b in zip(old, [o(int(e)) for o in own], strict=True)]
        t1 = time.process_time()
        mn = [est(int(e), b.z, b.s_min) for est, b in zip(new, vs(int(e)), strict=True)]
        cost["own"] += t1 - t0
        cost["variants"] += time.process_time() - t1
        for i in range(len(scns)):
            lists[i] += _count(mo[i], mn[i], names[i], count[i], sel[i])
    out: dict = {"epochs": int(epochs.size)}
    for i in range(len(scns)):
        out[str(i)] = _shares(epochs.size, lists[i], names[i], count[i], sel[i])
    out["ms_per_epoch"] = {k: 1e3 * v / epochs.size for k, v in cost.items()}
    return out


def main() -> None:  # pragma: no cover - command line
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--realization", type=int, default=1)
    ap.add_argument("--first", type=int, default=1500)
    ap.add_argument("--epochs", type=int, default=300)
    ap.add_argument("--out", default=None)
    ap.add_argument("--dump", default=None, help="write this version's engine decisions here (pickle)")
    ap.add_argument("--against", nargs=2, default=None, metavar=("OLD", "NEW"), help="compare two dumps")
    a = ap.parse_args()
    if a.against:
        dumps = []
        for path in a.against:
            with open(path, "rb") as fh:
                dumps.append(pickle.load(fh))
        res = compare_decisions(*dumps)
    else:
        with open(a.config, encoding="utf-8") as fh:
            cfg = yaml.safe_load(fh)
        epochs, key = np.arange(a.first, a.first + a.epochs), spawn_key("nr", a.realization)
        scn = scenario_from_config(cfg["nr"])
        if a.dump:
            with open(a.dump, "wb") as fh:
                pickle.dump(engine_decisions(scn, cfg["seed"], key, epochs), fh)
            return
        res = compare(scn, cfg["seed"], key, epochs)
    text = json.dumps(res, indent=2)
    if a.out:
        with open(a.out, "w", encoding="utf-8") as fh:
            fh.write(text + "\n")
    print(text)


if __name__ == "__main__":  # pragma: no cover
    main()
