"""The joint decision's power correction judged against the truth (reconstruction eq. 9–12).

Node i of the train triggers at X_i = Xm + Δx(ĉ_i): ĉ_i is its gap's deviation from the head's
fitted model Ĝ, predicted (WSLR) from the deviations its predecessors measured at their own
triggers. Its *true* deviation is what it would see without measurement noise: the true
local-mean gap (path loss and shadowing) at its true position at its trigger, minus the model
at its estimated position. The distance trigger at the band midpoint — the joint decision
without the correction — predicts 0. Per node this module returns

* the correction's error ĉ_i − d_i (d_i the true deviation);
* the midpoint trigger's error: −d_i at the node's own trigger without the correction (when
  its estimated position reaches Xm);
* an oracle's error, the same WSLR fed with the predecessors' *true* deviations: what is left
  when measurement noise and the L3 filter are removed (the deviation's change between the
  predecessors' trigger points and node i's, the position error);
* one measured deviation's error (measured minus true): the noise a single predecessor brings.

The correction helps a node when its error is smaller than the midpoint's.
"""

from __future__ import annotations

import numpy as np

from railradio.handover.band import geometric_weights, model_gap_db, wslr_predict
from railradio.handover.model import BlockContext
from railradio.handover.policies import head_band, joint_nodes

PARTS = ("correction", "midpoint", "oracle", "measured")
"""The error columns of :func:`correction_errors` (see the module docstring)."""


def correction_errors(ctx: BlockContext, m: int, alpha: float, method: str) -> dict[str, np.ndarray]:
    """Per run and node [B, N] [dB]: ``pred`` (ĉ_i), ``true`` (d_i) and the errors of
    :data:`PARTS` (node 0, the head, has no predecessor: NaN).

    Parameters
    ----------
    ctx : BlockContext
        The block's radio and position arrays (from
        :func:`railradio.handover.model.build_context`).
    m : int
        Number of joint nodes m: a node's prediction uses its min(m, i) nearest predecessors.
    alpha : float
        Geometric weight parameter α [1], in (0, 1).
    method : str
        WSLR reading, ``regression`` or ``mean``.

    Returns
    -------
    dict of str to numpy.ndarray
        Arrays [B, N] [dB], column 0 (the head) NaN: ``pred``, the deviation ĉ_i predicted by
        WSLR from the predecessors' measured deviations; ``true``, the true deviation d_i at the
        node's trigger; the errors ``correction`` (ĉ_i − d_i), ``midpoint`` (−d_i at the node's
        trigger without the correction, when its estimate reaches Xm), ``oracle`` (WSLR of the
        predecessors' true deviations minus d_i) and ``measured`` (the node's measured minus its
        true deviation).

    Raises
    ------
    ValueError
        If ``m`` is not an integer ≥ 1, ``alpha`` is outside (0, 1), or ``method`` is neither
        ``regression`` nor ``mean`` (checked when the train has more than one node).
    """
    w = geometric_weights(m, alpha)
    band = head_band(ctx)
    nodes = joint_nodes(ctx, band, w[None, :], method)
    k = nodes["k"][0]
    b_n, n_n = k.shape
    rows = np.broadcast_to(np.arange(b_n)[:, None], k.shape)
    offs = ctx.kin.node_offsets_m[None, :]
    x_true = ctx.kin.x_head_m[k] - offs
    x_hat = ctx.xhat_head_m[rows, k] - offs
    p_s, p_t = ctx.true_rsrp_dbm(rows, x_true)
    d = (p_s - p_t) - model_gap_db(x_hat, band.a_db[:, None], band.n_hat[:, None], ctx.scn.radio)
    # without the correction every node triggers when its estimate reaches Xm
    k_mid = ctx.first_passage(band.xm_m[None, :] + ctx.kin.node_offsets_m[:, None]).T  # [B, N]
    x_true_mid = ctx.kin.x_head_m[k_mid] - offs
    x_hat_mid = ctx.xhat_head_m[rows, k_mid] - offs
    ps_m, pt_m = ctx.true_rsrp_dbm(rows, x_true_mid)
    d_mid = (ps_m - pt_m) - model_gap_db(x_hat_mid, band.a_db[:, None], band.n_hat[:, None], ctx.scn.radio)
    pred = nodes["pred_db"][0]
    oracle = np.zeros((b_n, n_n))
    for i in range(1, n_n):
        p = min(m, i)
        oracle[:, i] = wslr_predict(d[:, i - p : i][:, ::-1], w[None, :], method)
    out = {
        "pred": pred,
        "true": d,
        "correction": pred - d,
        "midpoint": -d_mid,
        "oracle": oracle - d,
        "measured": nodes["dev_db"][0] - d,
    }
    for v in out.values():
        v[:, 0] = np.nan
    return out


def rms_per_node(err: np.ndarray) -> np.ndarray:
    """Root-mean-square over runs of an error [B, N] per node [N] (NaN for the head).

    Parameters
    ----------
    err : numpy.ndarray
        Errors [B, N] over runs and nodes (e.g. [dB]); non-finite entries are left out.

    Returns
    -------
    numpy.ndarray
        RMS over the finite runs of each node [N], in the unit of ``err``; NaN for a node
        without a finite value (the head).
    """
    e = np.asarray(err, dtype=float)
    ok = np.isfinite(e)
    n = ok.sum(axis=0)
    ss = np.where(ok, e * e, 0.0).sum(axis=0)
    return np.where(n > 0, np.sqrt(ss / np.maximum(n, 1)), np.nan)


def correction_dataset(scn, speeds_kmh: list[float], seed: int, n_blocks: int, runs_per_block: int):
    """RMS errors per node of :data:`PARTS` at each speed, on the sweep's first ``n_blocks``
    blocks of crossings (the same draws as the sweep), with the predicted-against-true
    scatter of every node: an :class:`xarray.Dataset`.

    Parameters
    ----------
    scn : Scenario
        The scenario with the joint weights set (``joint.m``, ``joint.alpha``; ``joint.wslr``
        is the WSLR reading).
    speeds_kmh : list of float
        Train speeds [km/h], each 1–1000.
    seed : int
        Root seed of the sweep.
    n_blocks : int
        Blocks of crossings per speed (blocks 0…n_blocks − 1 of the ``sweep`` stream).
    runs_per_block : int
        Train crossings per block, ≥ 1.

    Returns
    -------
    xarray.Dataset
        ``rms_db`` [dB] (speed, part, node): RMS over crossings of each part's error (NaN for
        the head); ``pred_db`` and ``true_db`` [dB] (speed, run, node): predicted ĉ_i and true
        deviation d_i; ``corr`` [1] (speed): their correlation.  Coordinates ``speed``
        [km/h], ``part`` (:data:`PARTS`), ``node`` (1 = head), ``run``.

    Raises
    ------
    ValueError
        If ``joint.m`` or ``joint.alpha`` is not set or invalid, a speed is out of range, or
        ``runs_per_block`` < 1.
    """
    import xarray as xr

    from railradio.handover.model import build_context, draw_block
    from railradio.handover.train import kinematics

    jt = scn.joint
    rms = np.full((len(speeds_kmh), len(PARTS), scn.train.n_nodes), np.nan)
    preds, trues, corr = [], [], np.full(len(speeds_kmh), np.nan)
    for s, v in enumerate(speeds_kmh):
        kin = kinematics(scn, v)
        parts = {p: [] for p in ("pred", "true") + PARTS}
        for b in range(n_blocks):
            ctx = build_context(scn, kin, draw_block(seed, v, b, runs_per_block, kin, scn.train.n_nodes, "sweep"))
            out = correction_errors(ctx, jt.m, jt.alpha, jt.wslr)
            for p in parts:
                parts[p].append(out[p])
        cat = {p: np.concatenate(a, axis=0) for p, a in parts.items()}
        for j, p in enumerate(PARTS):
            rms[s, j] = rms_per_node(cat[p])
        ok = np.isfinite(cat["pred"]) & np.isfinite(cat["true"])
        corr[s] = float(np.corrcoef(cat["pred"][ok], cat["true"][ok])[0, 1]) if ok.sum() > 2 else np.nan
        preds.append(cat["pred"])
        trues.append(cat["true"])
    n_runs = n_blocks * runs_per_block
    return xr.Dataset(
        {
            "rms_db": (
                ("speed", "part", "node"),
                rms,
                {
                    "units": "dB",
                    "long_name": "RMS over crossings of the error of the predicted deviation: the "
                    "correction's, the midpoint trigger's (0 predicted), an oracle's fed "
                    "the predecessors' true deviations, one measured deviation's",
                },
            ),
            "pred_db": (
                ("speed", "run", "node"),
                np.stack(preds),
                {"units": "dB", "long_name": "deviation from the head's model predicted for the node (WSLR)"},
            ),
            "true_db": (
                ("speed", "run", "node"),
                np.stack(trues),
                {
                    "units": "dB",
                    "long_name": "the node's true deviation at its trigger: true local-mean gap "
                    "minus the model at its estimated position",
                },
            ),
            "corr": (("speed",), corr, {"units": "1", "long_name": "correlation of predicted and true deviation"}),
        },
        coords={
            "speed": ("speed", np.asarray(speeds_kmh, float), {"units": "km/h", "long_name": "train speed"}),
            "part": ("part", list(PARTS), {"units": "1", "long_name": "what predicts the deviation"}),
            "node": ("node", np.arange(scn.train.n_nodes) + 1, {"units": "1", "long_name": "relay-AP node (1 = head)"}),
            "run": ("run", np.arange(n_runs), {"units": "1", "long_name": "crossing"}),
        },
    )


def correction_key_numbers(ds) -> dict:
    """Key numbers ``handover.correction.*``: per speed the RMS errors averaged over the
    nodes behind the head, the share of those nodes the correction helps (its error below
    the midpoint trigger's) and the correlation of predicted and true deviations.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset of :func:`correction_dataset`.

    Returns
    -------
    dict of str to dict
        Key name -> JSON entry (:meth:`railradio.keynumbers.KeySpec.entry`): per speed tag
        ``v<speed>``, ``handover.correction.<part>_rms_db.v<speed>`` [dB] for each of
        :data:`PARTS`, ``handover.correction.helps_node_frac.v<speed>`` [1] and
        ``handover.correction.corr.v<speed>`` [1].

    Raises
    ------
    ValueError
        If a value is not finite (e.g. a NaN correlation with too few samples).
    """
    from railradio.keynumbers import KeySpec

    out = {}
    for v in ds["speed"].values:
        tag = f"v{float(v):g}"
        r = ds["rms_db"].sel(speed=v).isel(node=slice(1, None))
        for p in PARTS:
            name = f"handover.correction.{p}_rms_db.{tag}"
            out[name] = KeySpec(
                name,
                "dB",
                f"RMS error of the deviation predicted by the {p} column, mean over the "
                f"nodes behind the head, {float(v):g} km/h",
            ).entry(float(r.sel(part=p).mean()))
        helps = float((r.sel(part="correction") < r.sel(part="midpoint")).mean())
        name = f"handover.correction.helps_node_frac.{tag}"
        out[name] = KeySpec(
            name,
            "1",
            f"share of the nodes behind the head whose trigger the power correction brings "
            f"closer to the truth than the band midpoint, {float(v):g} km/h",
        ).entry(helps)
        name = f"handover.correction.corr.{tag}"
        out[name] = KeySpec(name, "1", f"correlation of the predicted and the true deviation, {float(v):g} km/h").entry(
            float(ds["corr"].sel(speed=v))
        )
    return out


def plot_correction(ds, pdf: str, png: str) -> None:
    """RMS error per node of each predictor, one panel per speed.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset of :func:`correction_dataset` (``rms_db`` [dB] over speed, part, node).
    pdf : str
        Path of the PDF to write.
    png : str
        Path of the PNG to write.
    """
    from railradio import plotting

    speeds = ds["speed"].values
    fig, axes = plotting.figure(ncols=len(speeds), figsize=(3.4 * len(speeds), 3.0), squeeze=False, sharey=True)
    style = {
        "correction": ("C0", "-", "power correction (WSLR of measured deviations)"),
        "midpoint": ("C1", "--", "no correction: band midpoint"),
        "oracle": ("C2", ":", "WSLR of the true deviations (oracle)"),
        "measured": ("grey", "-.", "one measured deviation's noise"),
    }
    for ax, v in zip(axes[0], speeds, strict=True):
        for p in PARTS:
            c, ls, lab = style[p]
            ax.plot(
                ds["node"],
                ds["rms_db"].sel(speed=v, part=p),
                color=c,
                linestyle=ls,
                marker="o",
                markersize=3,
                label=lab,
            )
        ax.set_xlabel("node (1 = head)")
        ax.set_title(f"{float(v):g} km/h", fontsize=8)
    axes[0][0].set_ylabel("RMS error of the node's deviation [dB]")
    axes[0][0].legend(fontsize=6)
    plotting.save(fig, pdf, png)
