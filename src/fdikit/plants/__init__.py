"""Benchmark plants as library data.

Each plant is a function returning a :class:`~fdikit.model.FaultModel`; :data:`PLANTS`
maps a short name to that function and :func:`~fdikit.plants.registry.get_plant` looks one up by name.

===================  ==============================================  ======================
name                 model                                            source
===================  ==============================================  ======================
``path12``           PATH vehicle, 12 states, sensor-fault design     Douglas et al. 1996, (d.2)
``path14``           PATH vehicle, 14 states, actuator-fault design   Douglas et al. 1996, (d.1)
``single-track``     lateral single-track model with lane errors      van der Ploeg 2018, (B.12)
``f16xl``            F-16XL longitudinal, 4 states, ``C = I``         Murray 2012, §6.1
``f16xl-gust``       F-16XL, 5 states with Dryden gust, 4 sensors     Douglas et al. 1996, App. C.5
``white-speyer``     3-state system with invariant-zero cases         Murray 2012, §6.2
``varrier-lateral``  lateral 2-state model, ρ = 1/v, Euler 0.02 s     Varrier et al. 2014, (48)
``path7``            PATH longitudinal, 7 states (reduced, 25 m/s)    Douglas et al. 1996, §9.6
``msd``              3-mass spring-damper LPV benchmark (k1, m3)      Hallouzi 2008, §3.6
``b747``             B747 longitudinal FDI example (substitute B)     Hallouzi 2008, §2.4.1
===================  ==============================================  ======================

Examples
--------
>>> from fdikit.plants import get_plant
>>> get_plant("single-track", speed=25.0).states
('lateral_velocity', 'yaw_rate', 'lateral_error', 'heading_error')

* :mod:`fdikit.plants.registry` — The registry of benchmark plants: :data:`PLANTS` maps a short name to its
  constructor, :func:`get_plant` builds one.
* :mod:`fdikit.plants.path_vehicle` — PATH linear vehicle models of Douglas et al. 1996, Appendix D.
* :mod:`fdikit.plants.path_longitudinal` — PATH 7-state longitudinal car model: the game-filter example of Douglas
  et al. (1996), §9.6.
* :mod:`fdikit.plants.single_track` — Linear single-track (bicycle) lateral model with lane-error states (van der
  Ploeg 2018, App. B).
* :mod:`fdikit.plants.f16xl` — F-16XL longitudinal dynamics, the aircraft example of the game-theoretic and H∞
  filters.
* :mod:`fdikit.plants.white_speyer` — The three-state White–Speyer system: Murray 2012, §6.2 (Example 2).
* :mod:`fdikit.plants.varrier_lateral` — Renault Scénic lateral dynamics, LPV in ρ = 1/v (Varrier, Koenig & Martinez
  2014, §5.1, (47)–(48)).
* :mod:`fdikit.plants.msd` — Three-mass mass–spring–damper (MSD) LPV benchmark: Hallouzi 2008, §3.6 (after Fekri et
  al. 2006b).
* :mod:`fdikit.plants.b747` — Boeing 747 linear longitudinal FDI example: Hallouzi 2008, §2.4.1, (2.54)–(2.61),
  Tables 2.5–2.6.
* :mod:`fdikit.plants.b747_jsbsim` — B and C of the §2.4.1 B747 example from JSBSim's B747, in place of the lost
  (2.57)–(2.61): Hallouzi 2008, §2.4.1.
* :mod:`fdikit.plants.target_tracking` — The maneuvering-target tracking benchmark of Hallouzi 2008, §2.4.2,
  (2.65)–(2.68).
"""

import lazy_loader as lazy

__getattr__, __dir__, __all__ = lazy.attach(
    __name__,
    submod_attrs={
        "registry": [
            "PLANTS", "get_plant",
        ],
        "path_vehicle": [
            "CONTROLS", "OUTPUTS", "STATES_12", "STATES_14", "TABLE_2_1_EIGENVALUES_12", "TABLE_2_1_EIGENVALUES_14",
            "path_vehicle_12", "path_vehicle_14", "rounding_intervals",
        ],
        "path_longitudinal": [
            "PATH7_A", "PATH7_A_PRINTED", "PATH7_C", "PATH7_C_PRINTED", "PATH7_F_ACCEL_X", "PATH7_F_ENGINE_SPEED",
            "PATH7_OUTPUTS", "path_longitudinal_7", "path_longitudinal_7_fault_maps",
        ],
        "single_track": [
            "CONTROLS", "DISTURBANCES", "OUTPUTS", "PRIUS_2010", "SENSORS", "STATES", "SingleTrackLPV",
            "SingleTrackParameters", "sensor_selection", "single_track", "single_track_lpv", "understeer_gradient",
        ],
        "f16xl": [
            "F16XL_A", "F16XL_DRYDEN_GAIN", "F16XL_GUST_POLE", "f16xl_gust", "f16xl_longitudinal",
        ],
        "white_speyer": [
            "WHITE_SPEYER_CASES", "white_speyer",
        ],
        "varrier_lateral": [
            "CONTROLS", "OUTPUTS", "RHO_STAR", "SCENIC", "STATES", "T_D", "VarrierParameters", "rho_from_speed",
            "varrier_lateral", "varrier_lateral_continuous", "varrier_lateral_lpv", "varrier_uncertainty",
        ],
        "msd": [
            "MSD_CONSTANTS", "MSD_RANGES", "MSD_SAMPLE_TIME", "msd", "msd_matrices", "msd_model_vectors",
            "msd_parameter_grid", "msd_parameters_to_weights", "msd_weights_to_parameters",
        ],
        "b747": [
            "B747_FAULT_SCHEDULE", "B747_MODEL_NAMES", "B747_NOISE", "B747_STATES", "B747_TRANSITION",
            "b747_longitudinal", "b747_model_set",
        ],
        "b747_jsbsim": ["B747JSBSimMatrices", "b747_jsbsim_matrices"],
        "target_tracking": [
            "PI_TRACKING", "Q_TRACKING", "R_TRACKING", "TRACKING_MODES", "TS", "X0_TRACKING", "tracking_A",
            "tracking_B",
        ],
    },
)
