"""The factor of a noise channel to invert, for every case: standard co-outer or one of the reference's
non-standard options (``nonstd = 1 … 5``), for ``afdsyn`` (Procedure AFD) and ``amdsyn`` (Procedure AMD).

References
----------
Varga (2017), §5.3, §6.3, Remark 5.8; fdtools (``afdredsyn``, ``amdsyn``, ``nonstd``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from fdikit.design.nullspace.factorization import (
    CoOuterFactor,
    coouter_coinner,
    quasi_coouter,
    quasi_coouter_row,
    realization,
    regularized_coouter,
)
from fdikit.errors import DesignError

__all__ = ["NONSTD_OPTIONS", "noise_factor", "attenuate_noise"]

#: The non-standard options, the reference's ``nonstd = 1 … 5``.
NONSTD_OPTIONS = ("quasi", "regularize", "wiener-hopf", "wiener-hopf-shift", "wiener-hopf-regularize")


def noise_factor(A, B, C, D, dt: float | None = None, *, nonstd: str = "quasi", epsreg: float = 0.1,
                 poles: Sequence[complex] | None = None, sdeg: float | None = None, smarg: float | None = None,
                 sdegzer: float | None = None) -> CoOuterFactor:
    """The factor ``F`` of a noise channel ``R_w`` to invert (``Q ← F⁻¹ Q``): co-outer, or the chosen non-standard one.

    The standard co-outer factor when it exists (:func:`coouter_coinner`); otherwise, by the reference's
    ``nonstd = 1 … 5``: the quasi factor (:func:`quasi_coouter_row` for one continuous row, with ``smarg``;
    :func:`quasi_coouter` otherwise), the regularised factor, or a Wiener–Hopf factor
    (:func:`~fdikit.design.nullspace.row_factors.wiener_hopf_row` for one continuous row,
    :func:`~fdikit.design.nullspace.wiener_hopf.wiener_hopf` otherwise).

    Parameters
    ----------
    A, B, C, D : array_like
        A stable minimal realisation of ``R_w`` (full row rank).
    dt : float or None
        Sample time.
    nonstd : {"quasi", "regularize", "wiener-hopf", "wiener-hopf-shift", "wiener-hopf-regularize"}, default "quasi"
        The non-standard option.
    epsreg, poles, sdeg, smarg, sdegzer
        As :func:`~fdikit.design.nullspace.approximate.afdsyn`.

    Returns
    -------
    CoOuterFactor
        ``kind`` "standard", "quasi", "regularized" or the Wiener–Hopf option's name.

    Raises
    ------
    DesignError
        ``R_w`` without full row rank.
    ParameterError
        Bad options.

    Examples
    --------
    ``s/(s+2)`` has a zero at 0: non-standard; the quasi factor moves it to −0.05:

    >>> noise_factor([[-2.0]], [[-2.0]], [[1.0]], [[1.0]]).kind
    'quasi'

    References
    ----------
    Varga (2017), §5.3 (Procedure AFD), Remark 5.8; fdtools (``afdredsyn``, ``nonstd``).
    """
    from fdikit import validate
    from fdikit.design.nullspace.row_factors import wiener_hopf_row
    from fdikit.design.nullspace.wiener_hopf import wiener_hopf

    nonstd = validate.choice("nonstd", nonstd, NONSTD_OPTIONS)
    A, B, C, D = realization(A, B, C, D)
    try:
        return coouter_coinner(A, B, C, D, dt)
    except DesignError:
        if nonstd == "regularize":
            return regularized_coouter(A, B, C, D, dt, epsreg=epsreg)
        several = C.shape[0] > 1 or dt is not None
        if nonstd == "quasi":
            if several:
                return quasi_coouter(A, B, C, D, dt, poles=poles, sdeg=sdeg)
            return quasi_coouter_row(A, B, C, D, poles=poles, sdeg=-0.05 if sdeg is None else sdeg, smarg=smarg)
        job = {"wiener-hopf": "plain", "wiener-hopf-shift": "shift", "wiener-hopf-regularize": "regularize"}[nonstd]
        if several:
            f = wiener_hopf(A, B, C, D, dt, job=job, sdeg=sdeg, sdegzer=sdegzer, epsreg=epsreg)
            return CoOuterFactor(f.outer, None, dt, nonstd, f.shifted)
        F, moved = wiener_hopf_row(A, B, C, D, job=job, sdegzer=-0.05 if sdegzer is None else sdegzer,
                                   epsreg=epsreg)
        return CoOuterFactor(F, None, None, nonstd, moved)


def attenuate_noise(gen, model, *, channel=None, **options):
    """``F⁻¹ Q``: the filter ``gen`` times the inverse of the factor of its noise channel on ``model``.

    Parameters
    ----------
    gen : ResidualGenerator
        The filter ``Q``.
    model : FaultModel
        The plant with its noise inputs.
    channel : Channel, optional
        The minimal noise channel of ``gen`` on ``model``, when the caller has it already.
    **options
        ``nonstd``, ``epsreg``, ``poles``, ``sdeg``, ``smarg``, ``sdegzer`` of :func:`noise_factor`.

    Returns
    -------
    ResidualGenerator
        The new filter (minimal), with ``gen``'s signals and labels.
    CoOuterFactor
        The factor ``F``.

    Raises
    ------
    DesignError, ParameterError
        As :func:`noise_factor`.

    Examples
    --------
    A filter reading ``y`` of ``y = w`` with ``w`` through ``s/(s+2)`` gets ``F⁻¹`` of the quasi factor:

    >>> import numpy as np
    >>> from fdikit.model import FaultModel
    >>> from fdikit.residuals import ResidualGenerator
    >>> m = FaultModel([[-2.0]], [[-2.0]], Bw=[[1.0]], Dw=[[1.0]])
    >>> g = ResidualGenerator(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[1.0]], controls=(),
    ...                       outputs=m.outputs, residuals=("r",))
    >>> g2, fac = attenuate_noise(g, m)
    >>> fac.kind, g2.n
    ('quasi', 1)

    References
    ----------
    Varga (2017), §5.3 (Procedure AFD: ``Q ← R_wo⁻¹ Q``), §6.3 (Procedure AMD).
    """
    from fdikit.analysis.channels import minimal_channel
    from fdikit.design.nullspace.basis import minimal_realization
    from fdikit.design.nullspace.factorization import inverse, series

    ch = minimal_channel(gen.internal_form(model), list(model.noise)) if channel is None else channel
    fac = noise_factor(ch.A, ch.B, ch.C, ch.D, model.dt, **options)
    A, B, C, D = minimal_realization(*series((gen.A, gen.B, gen.C, gen.D), inverse(*fac.outer)))
    return dataclasses.replace(gen, A=A, B=B, C=C, D=D), fac
