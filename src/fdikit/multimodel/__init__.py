"""Multiple-model estimation and diagnosis (Hallouzi 2008): Kalman/EKF building blocks, the IMM filter,
convex-model filters and model-set design.

* :mod:`fdikit.multimodel.kalman_steps` — Kalman-filter steps on arrays: covariance (Joseph) form and square-root
  (QR) form.
* :mod:`fdikit.multimodel.kalman` — Discrete Kalman filter for one linear Gaussian model: batch runner and online
  filter.
* :mod:`fdikit.multimodel.ekf` — Extended Kalman filter with user Jacobians or central finite differences.
* :mod:`fdikit.multimodel.imm` — Interacting multiple-model (IMM) filter for jump-Markov linear systems.
* :mod:`fdikit.multimodel.isolation` — Fault isolation from multiple-model weights: the group-sum threshold logic of
  Hallouzi 2008, Table 4.7.
* :mod:`fdikit.multimodel.model_set` — Model vectors of a large model set and the helpers every model-set design
  shares: Hallouzi 2008, Ch. 3 and App. B.
* :mod:`fdikit.multimodel.od_design` — Orthogonal-decomposition (OD) model-set design: Hallouzi 2008, §3.3.2,
  (3.19)–(3.23).
* :mod:`fdikit.multimodel.cp_design` — CP model-set design: an enclosing convex polytope (Hallouzi 2008, §3.4,
  (3.25)–(3.33)), after Kanev (2006).
* :mod:`fdikit.multimodel.lv_design` — Limit-value (LV) model-set design: Hallouzi 2008, §3.5, (3.34)–(3.40).
* :mod:`fdikit.multimodel.observability` — Observability of multiple-model systems and the minimum-mismatch model set:
  Hallouzi 2008, §3.3.1 and §3.6.4.
* :mod:`fdikit.multimodel.convex` — Convex-model (CM) structure (Hallouzi 2008, §2.2.2) and its limit-value form
  (§3.5).
* :mod:`fdikit.multimodel.convex_filter` — The dual convex-model filter (Hallouzi 2008, §2.3.2, Table 2.2).
* :mod:`fdikit.multimodel.convex_ekf` — Augmented EKF for the convex-model structure (Hallouzi 2008, §2.3.3, Table
  2.3).
* :mod:`fdikit.multimodel.simplex` — Projection of convex-model weights on the simplex (Hallouzi 2008,
  (2.37)–(2.38)).
* :mod:`fdikit.multimodel.reconstruction` — Fault sizes, parameters and model vectors reconstructed from estimated
  weights (Hallouzi 2008, §3.6.2, (3.51)–(3.57)).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "kalman_steps": [
            "gaussian_log_likelihood", "kf_predict", "kf_update", "psd_sqrt", "srcf_step", "srkf_predict",
            "srkf_update",
        ],
        "kalman": [
            "KalmanFilter", "KalmanResult", "KalmanStep", "kalman_filter",
        ],
        "ekf": [
            "ExtendedKalmanFilter", "ekf_predict", "ekf_update", "extended_kalman_filter", "numerical_jacobian",
        ],
        "imm": [
            "IMMFilter", "IMMResult", "IMMStep", "IMMStepper",
        ],
        "isolation": [
            "GroupThresholdLogic", "mode_diagnosis", "most_probable_mode", "table_4_7_logic",
        ],
        "model_set": [
            "affine_weights", "first_order_discretize", "gap_rank", "nearest_model", "taylor_remainder_bound",
            "unvectorize", "vectorize",
        ],
        "od_design": [
            "ODModelSet", "od_model_set", "pivoted_qr",
        ],
        "cp_design": [
            "CPModelSet", "convex_weights", "cp_model_set", "fit_enclosing_polytope",
        ],
        "lv_design": [
            "LimitValueModelSet", "limit_value_model_set",
        ],
        "observability": [
            "minimum_mismatch_points", "observability_condition", "pair_observability",
        ],
        "convex": [
            "ConvexModelSet", "convex_model_set", "limit_value_convex_set",
        ],
        "convex_filter": [
            "ConvexFilterResult", "dual_convex_filter", "innovation_regressors", "rls_weight_step",
            "weight_regressors",
        ],
        "reconstruction": [
            "estimated_model_vector", "fault_size_from_weights", "lv_parameter", "lv_reciprocal_parameter",
        ],
        "convex_ekf": [
            "augmented_ekf", "augmented_jacobians",
        ],
        "simplex": [
            "constrain_weights", "project_to_affine", "project_to_simplex", "project_to_simplex_weighted",
        ],
    },
)
