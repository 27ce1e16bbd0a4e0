"""From per-RRH AOD/TOA measurements to a track: motion and measurement models (source eq. 10–14),
the AOD's error near endfire, snapshot fixes, the EKF and IMM, the RTS smoother, calibration on
a separate run, lost-track accounting, and the bounds.
"""

from railradio.nr.tracking.aod_model import endfire_angle, predicted_bias
from railradio.nr.tracking.bounds import (
    BETA_RMS_HZ,
    DETECT_E_OVER_N0,
    DETECT_K_SIGMA,
    INTEGER_SAMPLE_SIGMA_M,
    PSS_SSS_SUBCARRIERS,
    block_e_over_n0,
    burst_e_over_n0,
    change_epochs,
    detected_blocks,
    pcrb_m,
    peb_m,
    toa_crb_s,
)
from railradio.nr.tracking.calibration import (
    Q_SEARCH_LIMITS,
    calibrate,
    inlier_sigma,
    measurement_errors,
    robust_sigmas,
    selected,
)
from railradio.nr.tracking.candidates import MeasuredCandidates, anchor_x, select_measurements
from railradio.nr.tracking.dynamics import process_noise, transition
from railradio.nr.tracking.ekf import TrackerConfig, nees_position, run_ekf
from railradio.nr.tracking.imm import (
    ImmConfig,
    markov_matrix,
    position_nees,
    q_for_jump,
    run_imm,
    stationary,
    track_filters,
)
from railradio.nr.tracking.loss import ACCURACY_CAP_M, LOST_FRAC_MAX, accuracy, lost_mask, rrh_spacing_m, time_to_loss_s
from railradio.nr.tracking.measurement import (
    MEASUREMENT_SETS,
    distances_m,
    h_terms,
    hx,
    jac_terms,
    jacobian,
    residual_fn,
)
from railradio.nr.tracking.smoother import rts_smooth
from railradio.nr.tracking.snapshot import snapshot_ls, snapshot_ls_batch
from railradio.nr.tracking.track import TrackSetup, track, track_setup

__all__ = [
    "ACCURACY_CAP_M",
    "BETA_RMS_HZ",
    "DETECT_E_OVER_N0",
    "DETECT_K_SIGMA",
    "INTEGER_SAMPLE_SIGMA_M",
    "ImmConfig",
    "LOST_FRAC_MAX",
    "MEASUREMENT_SETS",
    "MeasuredCandidates",
    "PSS_SSS_SUBCARRIERS",
    "Q_SEARCH_LIMITS",
    "TrackSetup",
    "TrackerConfig",
    "accuracy",
    "anchor_x",
    "block_e_over_n0",
    "burst_e_over_n0",
    "calibrate",
    "change_epochs",
    "detected_blocks",
    "distances_m",
    "endfire_angle",
    "h_terms",
    "hx",
    "inlier_sigma",
    "jac_terms",
    "jacobian",
    "lost_mask",
    "markov_matrix",
    "measurement_errors",
    "nees_position",
    "pcrb_m",
    "peb_m",
    "position_nees",
    "predicted_bias",
    "process_noise",
    "q_for_jump",
    "residual_fn",
    "robust_sigmas",
    "rrh_spacing_m",
    "rts_smooth",
    "run_ekf",
    "run_imm",
    "select_measurements",
    "selected",
    "snapshot_ls",
    "snapshot_ls_batch",
    "stationary",
    "time_to_loss_s",
    "toa_crb_s",
    "track",
    "track_filters",
    "track_setup",
    "transition",
]
