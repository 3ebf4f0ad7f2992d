"""The recurrent logistic perceptron of the BNN with exact gradients (Douglas et al. 1996, Ch. 6, (6.1)).

``x¹_k = u_k + F y_{k−1}``, ``x^i_k = W^i y^{i−1}_k + θ^i``, ``y^i_k = S(x^i_k)``; the cost and its gradient are
back-propagated through the whole unrolled recurrence.  The training and the evaluator are in
:mod:`fdikit.decision.learned.bnn`, whose docstring describes the design choices.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.special import expit

from fdikit.errors import DataError, ParameterError

__all__ = ["BnnNetwork"]


class BnnNetwork:
    """The logistic network with one-step output feedback (6.1); weights live in a flat vector.

    ``w`` stacks ``W², θ², …, W^q, θ^q`` (row-major) and, when ``learn_feedback``, ``F`` last.
    Sequences are ``(B, T, n_in)`` arrays (or ``(T, n_in)``); a sample is used when ``valid`` and
    finite, otherwise the feedback state is held and the output repeats.

    Parameters
    ----------
    widths : sequence of int
        Layer widths ``(n_in, n_2, …, n_out)``: at least an input and an output layer, all positive.
    feedback : (n_in, n_out) array_like, optional
        ``F`` of ``x¹_k = u_k + F y_{k−1}``; default the rectangular identity.
    learn_feedback : bool, default False
        Train ``F`` along with the weights (it is then the last part of ``w``).

    Attributes
    ----------
    widths : tuple of int
        The layer widths.
    feedback : (n_in, n_out) ndarray
        ``F`` (the fixed one; when learned, the trained ``F`` is in the weight vector).
    learn_feedback : bool
        Whether ``F`` is part of ``w``.
    n_params : int
        Length of the flat weight vector ``w``.

    Raises
    ------
    ParameterError
        When there are fewer than two layers, a width is not positive, or ``feedback`` has the wrong shape or
        non-finite entries.

    References
    ----------
    Douglas et al. 1996, §6.1, (6.1) (the connections with one-step delayed output feedback, Fig. 6.1) and
    §6.3.1 (the mean-squared-error cost ``J``).

    Examples
    --------
    >>> import numpy as np
    >>> from fdikit.decision.learned.network import BnnNetwork
    >>> net = BnnNetwork((2, 3, 2))
    >>> w = net.init(np.random.default_rng(0))
    >>> net.n_params, net.forward(w, np.zeros((5, 2))).shape
    (17, (5, 2))
    >>> J, grad = net.cost_grad(w, np.ones((4, 2)), np.zeros((4, 2)))
    >>> grad.shape
    (17,)
    """

    def __init__(self, widths: Sequence[int], feedback=None, learn_feedback: bool = False) -> None:
        widths = tuple(int(n) for n in widths)
        if len(widths) < 2 or min(widths) < 1:
            raise ParameterError(
                f"a network needs at least an input and an output layer of positive width, got {widths}"
            )
        self.widths = widths
        F = np.eye(widths[0], widths[-1]) if feedback is None else np.asarray(feedback, dtype=float)
        if F.shape != (widths[0], widths[-1]) or not np.all(np.isfinite(F)):
            raise ParameterError(
                f"the feedback matrix must be finite with shape {(widths[0], widths[-1])}, got {F.shape}"
            )
        self.feedback, self.learn_feedback = F, bool(learn_feedback)
        self._shapes = [(widths[i], widths[i - 1]) for i in range(1, len(widths))]

    @property
    def n_params(self) -> int:
        return sum(a * b + a for a, b in self._shapes) + (self.feedback.size if self.learn_feedback else 0)

    def unpack(self, w) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:
        """``([W², …, W^q], [θ², …, θ^q], F)`` from the flat vector."""
        w = np.asarray(w, dtype=float)
        if w.shape != (self.n_params,):
            raise ParameterError(f"weight vector has shape {w.shape}, the network needs ({self.n_params},)")
        Ws, ths, k = [], [], 0
        for a, b in self._shapes:
            Ws.append(w[k : k + a * b].reshape(a, b))
            ths.append(w[k + a * b : k + a * b + a])
            k += a * b + a
        F = w[k:].reshape(self.feedback.shape) if self.learn_feedback else self.feedback
        return Ws, ths, F

    def init(self, rng: np.random.Generator, centre=None, gain: float = 4.0, noise: float = 0.5) -> np.ndarray:
        """Channel-wise initial weights: each input is routed through its own chain of units to its
        tied output.

        ``W^i = gain·R^i + N(0, noise²/n_{i−1})`` with ``R^i`` the rectangular identity (the last
        layer: ``Fᵀ``, zero-padded to the hidden width), and ``θ^i = −gain·R^i c^{i−1}``, which centres
        each routed sigmoid on its input's typical value (``c¹ = centre``, the mean of ``y¹``, default
        0.75; ``c^i = 1/2`` after).  ``gain = 4`` undoes the logistic's slope of 1/4 at the centre.
        """
        parts = []
        last = len(self._shapes) - 1
        c = np.broadcast_to(np.asarray(0.75 if centre is None else centre, dtype=float), (self.widths[0],))
        for i, (a, b) in enumerate(self._shapes):
            if i == last:
                route, k = np.zeros((a, b)), min(b, self.widths[0])
                route[:, :k] = self.feedback.T[:, :k]
            else:
                route = np.eye(a, b)
            W = gain * route + rng.normal(0.0, noise / np.sqrt(b), (a, b))
            parts += [W.ravel(), -gain * (route @ c)]
            c = np.full(a, 0.5)
        if self.learn_feedback:
            parts.append(self.feedback.ravel())
        return np.concatenate(parts)

    @staticmethod
    def _layers(Ws, ths, F, u, y_prev) -> list[np.ndarray]:
        """All layer outputs for one time step of a batch (rows): (6.1a–c)."""
        y = expit(u + y_prev @ F.T)
        out = [y]
        for W, th in zip(Ws, ths):
            y = expit(y @ W.T + th)
            out.append(y)
        return out

    def _prepare(self, U, valid):
        U = np.asarray(U, dtype=float)
        single = U.ndim == 2
        if single:
            U = U[None]
        if U.ndim != 3 or U.shape[2] != self.widths[0]:
            n = self.widths[0]
            raise DataError(f"network input has shape {U.shape}, need (B, T, {n}) or (T, {n})")
        ok = np.all(np.isfinite(U), axis=2)
        if valid is not None:
            ok &= np.asarray(valid, bool).reshape(ok.shape)
        U = np.where(ok[..., None], U, 0.0).transpose(1, 0, 2)
        return U, ok.T, single

    def forward(self, w, U, valid=None) -> np.ndarray:
        """Outputs ``y_k`` from the reset state ``y_{−1} = 0`` (``(B, T, n_out)``, or ``(T, n_out)``)."""
        Ws, ths, F = self.unpack(w)
        U, ok, single = self._prepare(U, valid)
        T, B = ok.shape
        y = np.zeros((B, self.widths[-1]))
        Y = np.empty((T, B, self.widths[-1]))
        for k in range(T):
            y = np.where(ok[k][:, None], self._layers(Ws, ths, F, U[k], y)[-1], y)
            Y[k] = y
        Y = Y.transpose(1, 0, 2)
        return Y[0] if single else Y

    def cost_grad(self, w, U, Z, cost_mask=None, valid=None) -> tuple[float, np.ndarray]:
        """``J = (1/N) Σ ‖z_k − y_k‖²`` over the samples in ``cost_mask`` (and valid), and ``∂J/∂w``.

        Back-propagation through time over the whole unrolled recurrence: the gradient reaches
        earlier samples through the feedback ``x¹_k = u_k + F y_{k−1}`` (and through held samples).
        """
        Ws, ths, F = self.unpack(w)
        U, ok, _ = self._prepare(U, valid)
        T, B = ok.shape
        Z = np.asarray(Z, dtype=float).reshape(B, T, -1).transpose(1, 0, 2)
        c = ok if cost_mask is None else ok & np.asarray(cost_mask, bool).reshape(B, T).T
        N = int(c.sum())
        if N == 0:
            raise DataError("no valid sample carries a cost; nothing to train on")
        c = c / N
        q = len(self.widths)
        every = ok.all(axis=1)
        WT = [W.T for W in Ws]
        acts = [np.empty((T, B, n)) for n in self.widths]
        Yprev = np.empty((T, B, self.widths[-1]))
        y = np.zeros((B, self.widths[-1]))
        for k in range(T):  # forward (6.1), the same arithmetic as _layers
            a = expit(U[k] + y @ F.T)
            acts[0][k] = a
            for i in range(1, q):
                a = expit(a @ WT[i - 1] + ths[i - 1])
                acts[i][k] = a
            Yprev[k] = y
            y = a if every[k] else np.where(ok[k][:, None], a, y)
        Y = np.concatenate([Yprev[1:], y[None]])  # the (held) output at each sample
        E = Y - Z
        J = float(np.sum(c[..., None] * E * E))
        Ey = 2.0 * c[..., None] * E
        der = [A * (1.0 - A) for A in acts]
        delta = [np.empty_like(A) for A in acts]  # δx^i_k = ∂J/∂x^i_k
        carry = np.zeros((B, self.widths[-1]))
        for k in range(T - 1, -1, -1):  # backward through time
            gy = Ey[k] + carry
            d = gy * der[-1][k]
            if not every[k]:
                d = np.where(ok[k][:, None], d, 0.0)
            delta[-1][k] = d
            for i in range(q - 1, 0, -1):
                d = (d @ Ws[i - 1]) * der[i - 1][k]
                delta[i - 1][k] = d
            carry = d @ F if every[k] else np.where(ok[k][:, None], d @ F, gy)
        parts = []
        for i in range(1, q):
            Di = delta[i].reshape(T * B, -1)
            parts += [(Di.T @ acts[i - 1].reshape(T * B, -1)).ravel(), Di.sum(axis=0)]
        if self.learn_feedback:
            parts.append((delta[0].reshape(T * B, -1).T @ Yprev.reshape(T * B, -1)).ravel())
        return J, np.concatenate(parts)
