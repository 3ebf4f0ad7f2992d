"""Independent reference computations shared by tests (plain loops, no fdikit code)."""

import numpy as np


def state_space_loop(A, B, C, D, v, x0):
    """Sample-by-sample x[k+1] = A x + B v, y = C x + D v: (y (N,p), x (N,n), x after the last sample)."""
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C, D))
    x = np.array(x0, dtype=float)
    X, Y = [], []
    for vk in v:
        X.append(x.copy())
        Y.append(C @ x + D @ vk)
        x = A @ x + B @ vk
    n, p = A.shape[0], C.shape[0]
    return np.array(Y).reshape(len(v), p), np.array(X).reshape(len(v), n), x
