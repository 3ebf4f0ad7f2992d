"""The PATH monitor with disturbance-attenuating filters: a game-theoretic bank on the report's fault groups.

The Beard–Jones bank places the filter eigenvalues for the geometry alone; at realistic sensor noise its
scaled residuals carry noise far above the nominal fault (on fdikit's car the fault-free rms of the vertical
accelerometer group is ≈ 150 times the nominal bias).  The seeds propose disturbance attenuation for exactly
this: the game-theoretic fault detection filter (Douglas et al. 1996, Ch. 9; Chung & Speyer 1998; Murray 2012,
§3.3) weights the sensor noise and the faults to be blocked and gives a Riccati (Kalman-like) gain.

:func:`path_game_bank` keeps the report's four groups (:data:`~fdikit.studies.path1996.bank.FILTER_GROUPS`)
and design models, and replaces each Beard–Jones filter by one single-fault game filter per fault of the
group, blocking the other faults of the group (:func:`~fdikit.design.game.single_fault.game_filter_bank`,
Murray 2012, §6.1.1), with the sensor-noise weight ``V`` the noise covariance of the 100 Hz sensors as a
continuous spectral density (``σ² Δt``).  Residuals are scaled as the report's (§5.1.1), so the bank plugs into
the same isolation logic and processors.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from fdikit.model import FaultModel

__all__ = ["path_game_bank", "GAME_WEIGHTS"]

#: Default weights: attenuation bound γ, complementary-fault weight M, output weight Q (Murray 2012, (3.29)–(3.30)).
GAME_WEIGHTS = {"gamma": 1e-6, "M": 0.01, "Q": 1e-6}


def path_game_bank(models: tuple[FaultModel, FaultModel], nominal: Mapping[str, float],
                   noise_std: Mapping[str, float], *, dt: float = 0.01, gamma: float = GAME_WEIGHTS["gamma"],
                   M: float = GAME_WEIGHTS["M"], Q: float = GAME_WEIGHTS["Q"]):
    """Design the game-theoretic PATH bank on the (12-state, 14-state) models.

    Parameters
    ----------
    models : (FaultModel, FaultModel)
        Continuous design models: the 12-state one for filters 1–3, the 14-state one for filter 4.
    nominal : mapping of str to float
        Nominal size of each of the 15 faults (the residual scaling).
    noise_std : mapping of str to float
        Per-sample sensor noise standard deviation at ``dt`` (names of the model's outputs).
    dt : float, default 0.01
        Sample time of the sensors [s] (the noise weight is ``σ² dt``).
    gamma, M, Q : float
        Game-filter weights (defaults :data:`GAME_WEIGHTS`).

    Returns
    -------
    PathBank
        Same fields as :func:`~fdikit.studies.path1996.bank.path_bank`: designs by filter, the stacked scaled
        continuous generator, the filter of each residual, the nominal sizes and the scale factors.

    Raises
    ------
    DesignError
        When a game Riccati equation has no admissible solution at these weights (the message names the fault).
    ParameterError
        For a missing noise level or nominal size.

    References
    ----------
    Douglas et al. 1996, Ch. 9 (the game-theoretic filter), §4.2 (the groups), §5.1.1 (the scaling); Murray 2012,
    §3.3, §6.1.1; Chung & Speyer 1998.

    Examples
    --------
    >>> from fdikit.studies.path1996.nonlinear_evaluation import NOISE_STD, evaluation_setup
    >>> s = evaluation_setup()  # doctest: +SKIP
    >>> bank = path_game_bank((s.models.model12, s.models.method1), s.nominal, NOISE_STD)  # doctest: +SKIP
    >>> sorted(bank.designs)  # doctest: +SKIP
    ['filter1', 'filter2', 'filter3', 'filter4']
    """
    from fdikit import validate
    from fdikit.design.game.single_fault import game_filter_bank
    from fdikit.errors import DesignError, ParameterError
    from fdikit.fault_maps import resolve_faults
    from fdikit.residuals import stack_generators
    from fdikit.studies.path1996.bank import FILTER_GROUPS, PathBank, scale_to_nominal

    dt = validate.positive("dt", dt)
    missing = [o for o in models[0].outputs if o not in noise_std]
    if missing:
        raise ParameterError(f"noise_std: no level for {missing}")
    sigma = np.array([validate.positive(f"noise_std[{o!r}]", noise_std[o]) for o in models[0].outputs])
    V = np.diag(sigma**2 * dt)
    designs, gens, groups, scales = {}, [], [], {}
    for name, specs in FILTER_GROUPS.items():
        base = models[1] if name == "filter4" else models[0]
        faults = [s.partition(":")[0] for s in specs]
        try:
            d = game_filter_bank(base, resolve_faults(base, specs), gamma=gamma, V=V, M=M, Q=Q)
        except DesignError as exc:
            raise DesignError(f"{name}: {exc}") from exc
        designs[name] = d
        g, group_scales = scale_to_nominal(name, base, d.generator, faults, nominal)
        scales.update(group_scales)
        gens.append(g)
        groups += [name] * len(g.residuals)
    return PathBank(designs, stack_generators(gens), tuple(groups), dict(nominal), scales)
