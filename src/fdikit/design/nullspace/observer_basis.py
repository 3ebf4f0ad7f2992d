"""The observer basis ``[−Gu I]`` of the reference's ``nullspace = false`` (Varga 2017, §5.2, Procedure EFD step 1).

Without disturbances, ``Q₁ = [−Gu I]`` (acting on ``[u; y]``) is a left annihilator of ``[Gu; I]`` of full row
rank ``p``: the residual ``y − ŷ`` of a copy of the plant driven by the controls, with ``R = Q₁ [Gf Gw; 0 0] =
[Gf Gw]``.  The reference uses it instead of the minimal proper basis when ``nullspace = false``; its rows are the
outputs, so ``HDesign`` (fdikit's ``selection``) combines output residuals, and the filter keeps the plant's order.
Poles of the plant beyond the stability margin are moved by a left coprime factor ``M̃ [−Gu I]`` (the reference's
``glcf``): an output injection ``L`` from SLICOT's Schur method (SB01BD, :func:`control.place_varga` on the dual,
which leaves the eigenvalues inside the margin where they are), so

    x̂' = (A − L C) x̂ + (Bu − L Du) u + L y,   r₁ = y − C x̂ − Du u,

and the observer residual is driven by the faults and the noise only, through ``(A − L C, [Bf − L Df, Bw − L Dw],
C, [Df Dw])`` — the *reduced model*.  The synthesis of the reference's step 2 onwards (the selection, the
decoupling of nuisance faults, the noise factor, the stabilisation) then acts on the reduced model, whose own basis
without nuisance faults is the identity (:func:`~fdikit.design.nullspace.basis.left_nullspace`), and the filter is
that second stage in series with ``Q₁``.  That is the reference's route for its banks (``efdisyn``: step 1 once,
then ``efdsyn`` per row on the reduced model).

With ``minimal = true`` the reference also lowers the order of ``H [Q₁ R]`` by a minimal dynamic cover
(``glmcover1``); fdikit applies the least order to the second stage only, so the filter has the plant's order plus
that of the second stage (``nullspace=True`` gives the least order).

Why by hand: no library forms the observer-based annihilator and its reduced model; the pole placement is SLICOT's.

References
----------
Varga (2017), §5.2 (the full-order observer basis ``[−Gu I]``, Procedure EFD), §7.5 (left coprime factorisation by
pole assignment); Varga (1981) (Schur method, SB01BD); fdtools (``efdsyn``/``afdsyn`` ``nullspace = false``,
``glcf``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fdikit.errors import DesignError, ParameterError
from fdikit.model import FaultModel
from fdikit.residuals import ResidualGenerator

__all__ = ["ObserverReduction", "observer_reduction"]


@dataclass(frozen=True, eq=False)
class ObserverReduction:
    """The first stage ``Q₁ = M̃ [−Gu I]`` and the model the second stage is designed on.

    Attributes
    ----------
    generator : ResidualGenerator
        ``Q₁`` on ``[u; y]``, one residual per output (named as the outputs).
    reduced : FaultModel
        ``R₁ = Q₁ [Gf Gw; 0 0]``: no controls, the faults and noise of the plant, one output per residual of ``Q₁``.
    injection : numpy.ndarray
        ``L`` (``n × p``; zero when no pole of the plant is beyond the margin).

    Examples
    --------
    >>> m = FaultModel([[1.0]], [[1.0], [1.0]], Bu=[[1.0]], Df=np.eye(2))
    >>> obs = observer_reduction(m, sdeg=-2.0)
    >>> np.linalg.eigvals(obs.reduced.A).round(6).tolist(), obs.reduced.outputs
    ([-2.0], ('y0', 'y1'))

    References
    ----------
    Varga (2017), §5.2, §7.5.
    """

    generator: ResidualGenerator
    reduced: FaultModel
    injection: np.ndarray

    def compose(self, design, model: FaultModel):
        """``design`` (made on :attr:`reduced`) in series with ``Q₁``: the same design on ``model``'s ``[u; y]``.

        Parameters
        ----------
        design : NullspaceDesign or ApproximateDesign
            The second stage.
        model : FaultModel
            The plant.

        Returns
        -------
        The design with the composed generator, its order and poles, and ``model``.

        References
        ----------
        Varga (2017), §5.2 (``Q = Q₂ Q₁``).
        """
        from fdikit.design.nullspace.basis import minimal_realization
        from fdikit.design.nullspace.factorization import series

        q1, q2 = self.generator, design.generator
        A, B, C, D = minimal_realization(*series((q1.A, q1.B, q1.C, q1.D), (q2.A, q2.B, q2.C, q2.D)), tol=1e-10)
        gen = dataclasses.replace(q2, A=A, B=B, C=C, D=D, controls=model.controls, outputs=model.outputs)
        poles = np.linalg.eigvals(A) if A.shape[0] else np.zeros(0, complex)
        return dataclasses.replace(design, generator=gen, order=A.shape[0], poles=poles, model=model)


def _margin(dt: float | None, smarg: float | None) -> float:
    eps = np.sqrt(np.finfo(float).eps)
    if smarg is not None:
        return float(smarg)
    return -eps if dt is None else 1.0 - eps


def observer_reduction(model: FaultModel, *, poles: Sequence[complex] | None = None, sdeg: float | None = None,
                       smarg: float | None = None) -> ObserverReduction:
    """The observer basis ``M̃ [−Gu I]`` of a plant without disturbances and its reduced model.

    Parameters
    ----------
    model : FaultModel
        The plant (controls, faults, noise; no disturbances).
    poles : sequence of complex, optional
        Where the plant's poles beyond the margin go (the first as many as there are; complex ones in pairs).
    sdeg : float, optional
        Their location when ``poles`` is None (default −0.05, discrete 0.95, as the basis denominators).
    smarg : float, optional
        The stability margin: poles with real part (discrete: modulus) at or above it are moved (default: the
        stability boundary).

    Returns
    -------
    ObserverReduction

    Raises
    ------
    ParameterError
        Disturbances in the model (their decoupling needs the nullspace basis), or too few ``poles``.
    DesignError
        When SLICOT cannot place the poles.

    Examples
    --------
    >>> m = FaultModel([[-1.0]], [[1.0]], Bu=[[1.0]], Bf=[[1.0]])
    >>> obs = observer_reduction(m)
    >>> obs.generator.D.tolist(), obs.injection.tolist()          # r = y − ŷ, the stable plant copied as it is
    ([[-0.0, 1.0]], [[0.0]])

    References
    ----------
    Varga (2017), §5.2, §7.5; Varga (1981).
    """
    import control as ct

    from fdikit.design.nullspace.basis import default_sdeg, minimal_realization

    if model.disturbances:
        raise ParameterError("nullspace=False (the observer basis [−Gu I]) needs a model without disturbances: "
                             f"decoupling {list(model.disturbances)} needs the nullspace basis (nullspace=True)")
    mu, mf = len(model.controls), len(model.faults)       # no disturbances: B = [Bu Bf Bw]
    A, B, C, D = minimal_realization(model.A, model.B, model.C, model.D, tol=1e-10)
    n, p = A.shape[0], C.shape[0]
    L = np.zeros((n, p))
    if n:
        alpha = _margin(model.dt, smarg)
        ev = np.linalg.eigvals(A)
        moved = ev[(ev.real if model.dt is None else np.abs(ev)) >= alpha]
        k = moved.size
        if k:
            sdeg = default_sdeg(model.dt) if sdeg is None else float(sdeg)
            want = list(poles)[:k] if poles is not None else [sdeg] * k
            if len(want) < k:
                raise ParameterError(f"poles has {len(want)} entries; the observer basis moves {k} plant poles")
            try:
                L = ct.place_varga(A.T, C.T, want, dtime=model.dt is not None, alpha=alpha).T
            except Exception as err:   # slycot's SB01BD errors (an unassignable eigenvalue)
                raise DesignError(f"the observer basis cannot move the plant poles {moved.round(6).tolist()} "
                                  f"(SB01BD: {err}); use nullspace=True") from err
    m = FaultModel(A, C, Bu=B[:, :mu], Du=D[:, :mu], Bf=B[:, mu:mu + mf], Df=D[:, mu:mu + mf], Bw=B[:, mu + mf:],
                   Dw=D[:, mu + mf:], controls=model.controls, faults=model.faults, noise=model.noise,
                   outputs=model.outputs, dt=model.dt)
    Ao = A - L @ C
    gen = ResidualGenerator(Ao, np.hstack([m.Bu - L @ m.Du, L]), -C, np.hstack([-m.Du, np.eye(p)]),
                            controls=model.controls, outputs=model.outputs, residuals=model.outputs, dt=model.dt)
    reduced = m.replace(A=Ao, Bu=np.zeros((n, 0)), Du=np.zeros((p, 0)), controls=(), Bf=m.Bf - L @ m.Df,
                        Bw=m.Bw - L @ m.Dw)
    return ObserverReduction(gen, reduced, L)

