"""Multiple-model estimation and diagnosis (Hallouzi 2008): Kalman/EKF building blocks, the IMM filter,
convex-model filters and model-set design.

* :mod:`fdikit.multimodel.kalman`, :mod:`fdikit.multimodel.ekf` — Kalman filter (covariance and square-root
  forms) and EKF, returning innovations, their covariances and log-likelihoods;
* :mod:`fdikit.multimodel.imm` — the IMM filter for jump-Markov linear systems (Table 2.1, corrected);
* :mod:`fdikit.multimodel.isolation` — the Table 4.7 isolation logic on mode probabilities;
* :mod:`fdikit.multimodel.model_set` — model-set design (Ch. 3, App. B);
* :mod:`fdikit.multimodel.convex`, :mod:`fdikit.multimodel.convex_ekf` — convex-model filters (dual filter and
  augmented EKF) and fault-size reconstruction from the weights.
"""

from fdikit.multimodel.convex import ConvexFilterResult, convex_model_set, dual_convex_filter
from fdikit.multimodel.convex_ekf import augmented_ekf
from fdikit.multimodel.cp_design import cp_model_set
from fdikit.multimodel.ekf import ExtendedKalmanFilter, NonlinearGaussianModel, extended_kalman_filter
from fdikit.multimodel.imm import IMMFilter, IMMResult
from fdikit.multimodel.isolation import GroupThresholdLogic, table_4_7_logic
from fdikit.multimodel.kalman import KalmanFilter, KalmanResult, LinearGaussianModel, kalman_filter
from fdikit.multimodel.model_set import limit_value_model_set, od_model_set

__all__ = [
    "ConvexFilterResult",
    "ExtendedKalmanFilter",
    "GroupThresholdLogic",
    "IMMFilter",
    "IMMResult",
    "KalmanFilter",
    "KalmanResult",
    "LinearGaussianModel",
    "NonlinearGaussianModel",
    "augmented_ekf",
    "convex_model_set",
    "cp_model_set",
    "dual_convex_filter",
    "extended_kalman_filter",
    "kalman_filter",
    "limit_value_model_set",
    "od_model_set",
    "table_4_7_logic",
]
