"""F-16XL longitudinal dynamics, the aircraft example of the game-theoretic and H∞ filters.

:func:`f16xl_longitudinal` is Murray 2012, §6.1 (Example 1, from Chen & Speyer 2002):
four states, every state measured (``C = I``), the elevon as control and the wind gust
as a disturbance.  The numbers are as printed; two consistency checks pin them (the gust
column equals column 2 of ``A``, checked in ``tests/plants/test_f16xl.py``, and ``−A e_4`` is
the printed magnitude column of ``F_θ``).

:func:`f16xl_gust` is the five-state version of Douglas et al. 1996, App. C.5 (the H∞
detection-filter example): the same airframe with a Dryden gust state and the sensors
q, α, A_z, A_x; its damaged printed data are reconstructed as documented there.
"""

from __future__ import annotations

import numpy as np

from fdikit import validate
from fdikit.errors import ParameterError
from fdikit.model import FaultModel

__all__ = ["f16xl_longitudinal", "F16XL_A", "f16xl_gust", "F16XL_DRYDEN_GAIN", "F16XL_GUST_POLE"]

#: State matrix of Murray 2012, §6.1 (states u, w in ft/s, q in deg/s, θ in deg).
F16XL_A = np.array(
    [
        [-0.0674, 0.0430, -0.8886, -0.5587],
        [0.0205, -1.4666, 16.5800, -0.0299],
        [0.1377, -1.6788, -0.6819, 0.0],
        [0.0, 0.0, 1.0, 0.0],
    ]
)
_B_ELEVON = np.array([[-0.1672], [-1.5179], [-9.7842], [0.0]])
_B_GUST = np.array([[0.0430], [-1.4666], [-1.6788], [0.0]])


def f16xl_longitudinal() -> FaultModel:
    """F-16XL longitudinal model of Murray 2012, §6.1 (Example 1).

    Returns
    -------
    FaultModel
        States ``u, w, q, theta``; outputs ``y_u, y_w, y_q, y_theta`` (``C = I``); control
        ``elevon``; disturbance ``gust`` (``B_wg`` = column 2 of ``A``).  The three faults of
        the example are named by :func:`fdikit.fault_maps.resolve_faults`: ``'y_theta_sensor'`` (the
        pitch-angle sensor, ``[e_4, A e_4]``), ``'elevon_actuator'`` (``F_δ = B_δ``) and the gust
        as a fault map ``{'gust': model.Bd}``.

    References
    ----------
    Murray 2012, §6.1 (Example 1).

    Examples
    --------
    >>> m = f16xl_longitudinal()
    >>> m.n, m.p, m.controls, m.disturbances
    (4, 4, ('elevon',), ('gust',))
    """
    return FaultModel(
        F16XL_A,
        np.eye(4),
        Bu=_B_ELEVON,
        Bd=_B_GUST,
        states=("u", "w", "q", "theta"),
        outputs=("y_u", "y_w", "y_q", "y_theta"),
        controls=("elevon",),
        disturbances=("gust",),
    )


# ---------------------------------------------------------------------- Douglas et al. 1996, App. C.5
#: First-order Dryden gust pole of Douglas et al. 1996, App. C.5 (``A(5,5) = −V/L_w``, 1/s).
F16XL_GUST_POLE = -1.1948
#: ``sqrt(2 V/L_w)``: the gust-filter gain that gives a unit gust variance (1 ft/s rms) from unit-PSD
#: white noise.  The report prints ``B_ω(5) = 1.57`` (gust variance 1.03 (ft/s)²); with 1.57 the
#: γ = 1.2 design of App. C.5 has no steady state (γ_min ≈ 1.21), with this value it has one.
F16XL_DRYDEN_GAIN = float(np.sqrt(-2.0 * F16XL_GUST_POLE))


def f16xl_gust(
    *,
    gust_gain: float = 1.57,
    pitch_rate_noise: float = 0.01,
    az_w_coefficient: float = -1.0517,
) -> FaultModel:
    """F-16XL longitudinal model with a first-order Dryden gust state (Douglas et al. 1996, App. C.5).

    Five states ``u, w`` (ft/s), ``q`` (deg/s), ``theta`` (deg), ``w_g`` (ft/s; the gust, entering
    like ``w``); outputs ``y_q`` (deg/s), ``y_alpha`` (deg), ``y_Az``, ``y_Ax`` (ft/s²); control
    ``elevon`` (deg); noise inputs (unit-PSD white) ``wind`` (through ``B_ω = gust_gain e_5``) and
    the sensor noises ``nu_q, nu_alpha, nu_Az, nu_Ax`` (through ``D = diag(d_q, 0.143, 0.245, 0.245)``).
    The faults of the example are named through :func:`fdikit.fault_maps.resolve_faults`:
    ``'y_Az_sensor'`` (the normal accelerometer, ``[F¹, A F¹]`` with ``C F¹ = e_3``) and
    ``'elevon_actuator'`` (``F_δ = B_δ``).  ``A[:4, :4]`` and ``B_δ[:4]`` are Murray's §6.1 model (:data:`F16XL_A`).

    The printed data (Douglas et al. 1996, App. C.5) are damaged in the transcription; the
    reconstruction:

    * ``A(1,5) = 0.0430`` (printed "0.04 130"): the gust column equals the ``w`` column in rows
      1–3, as ``w_g`` enters like ``w`` (and as Murray's gust input is column 2 of ``A``).
    * ``B_δ(1) = −0.1672``: the sign is lost in the print; Murray 2012, §6.1 prints −0.1672.
    * ``C(2,4) = 0`` (row 2 prints a stray "1.0000"): the printed ``F_Az`` needs ``C e_4 ∝ e_3``
      (``F¹ = e_4 / C(3,4)``, ``A F¹`` normalised = [0.9986, 0.0534, 0, 0, 0] as printed).
    * ``C(3,2)`` = ``az_w_coefficient``: printed "1.0517" without a legible sign.  −1.0517 is the
      default: it has the sign of ``A(2,2)`` like the u and θ entries of the row have the signs of
      ``A(2,1)``, ``A(2,4)``, and it reproduces the printed filter eigenvalue −0.435 (−0.39 against
      −0.75 with +1.0517) and the enhancement direction (|cos| 0.998 against 0.996).
    * ``d_q`` = ``pitch_rate_noise`` (unreadable ``D(1,1)``): 0.01 is fitted — with it the γ = 1.2
      design reproduces the printed eigenvalues −29.46, −1.61, −1.10 within 10 % (the fastest
      pole scales like 1/d_q).  ``D Dᵀ`` must be invertible, so ``d_q > 0``.
    * ``B_ω(5)`` = ``gust_gain``: printed 1.57; :data:`F16XL_DRYDEN_GAIN` (1.5459) is the
      alternative that makes the printed γ = 1.2 feasible.

    Parameters
    ----------
    gust_gain : float, default 1.57
        ``B_ω(5)``, the gain from the unit-PSD ``wind`` noise to the gust state [ft/s per unit noise];
        1.57 as printed, :data:`F16XL_DRYDEN_GAIN` for a unit gust variance.
    pitch_rate_noise : float, default 0.01
        ``d_q = D(1,1)``, the pitch-rate sensor noise gain [deg/s]; finite and ``>= 0`` (``> 0`` for
        designs that need ``D Dᵀ`` invertible).
    az_w_coefficient : float, default -1.0517
        ``C(3,2)``, the ``w`` entry of the normal-acceleration output row.

    Returns
    -------
    FaultModel
        Continuous model with 5 states, 4 outputs, the control ``elevon`` and 5 noise inputs
        ``wind, nu_q, nu_alpha, nu_Az, nu_Ax`` (no disturbance or fault inputs).

    Raises
    ------
    ParameterError
        If a coefficient is not a finite number, or ``pitch_rate_noise`` is negative or not finite.

    References
    ----------
    Douglas et al. 1996, App. C.5; Murray 2012, §6.1 (the airframe ``A[:4, :4]``, ``B_δ``).

    Examples
    --------
    >>> m = f16xl_gust()
    >>> m.n, m.outputs, m.noise[0]
    (5, ('y_q', 'y_alpha', 'y_Az', 'y_Ax'), 'wind')
    """
    gust_gain = validate.number("gust_gain", gust_gain)
    az_w_coefficient = validate.number("az_w_coefficient", az_w_coefficient)
    pitch_rate_noise = validate.number("pitch_rate_noise", pitch_rate_noise, finite=False)
    if not (np.isfinite(pitch_rate_noise) and pitch_rate_noise >= 0):
        raise ParameterError(f"pitch_rate_noise must be a finite standard deviation >= 0, got {pitch_rate_noise!r}")
    A = np.zeros((5, 5))
    A[:4, :4] = F16XL_A
    A[:3, 4] = F16XL_A[:3, 1]
    A[4, 4] = F16XL_GUST_POLE
    B_delta = np.vstack([_B_ELEVON, [[0.0]]])
    C = np.array(
        [
            [0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0591, 0.0, 0.0, 0.0],
            [0.0139, az_w_coefficient, 0.1485, -0.0299, 0.0],
            [-0.0677, 0.0431, 0.0171, 0.0, 0.0],
        ]
    )
    Bw = np.zeros((5, 5))
    Bw[4, 0] = gust_gain
    Dw = np.zeros((4, 5))
    Dw[:, 1:] = np.diag([pitch_rate_noise, 0.143, 0.245, 0.245])
    return FaultModel(
        A,
        C,
        Bu=B_delta,
        Bw=Bw,
        Dw=Dw,
        states=("u", "w", "q", "theta", "w_g"),
        outputs=("y_q", "y_alpha", "y_Az", "y_Ax"),
        controls=("elevon",),
        noise=("wind", "nu_q", "nu_alpha", "nu_Az", "nu_Ax"),
    )
