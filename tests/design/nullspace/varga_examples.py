"""Plants of the reference's tests (FaultDetectionTools.jl test/test_efdsyn.jl, test_fdigenspec.jl), as FaultModels.

The matrices are the printed data of those tests (Varga 2017, Examples 5.2 and 5.4; Yuan et al. 1997; Niemann
1998; Xiong and Saif 2000, Example 1), and the one-output plants of test_afdsyn.jl's non-standard cases.
"""

import numpy as np

from fdikit.model import FaultModel


def yuan():
    """Yuan et al. (1997): n = 4, one control, 8 faults, 3 outputs."""
    A = np.array([[-1, 1, 0, 0], [1, -2, 1, 0], [0, 1, -2, 1], [0, 0, 1, -2.0]])
    Bu = np.array([[1.0, 0, 0, 0]]).T
    Bf = np.array([[1, 0, 0, 0, 1, 0, 0, 0], [0, 1, 0, 0, -1, 1, 0, 0], [0, 0, 1, 0, 0, -1, 1, 0],
                   [0, 0, 0, 1, 0, 0, -1, 1.0]])
    C = np.array([[1.0, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    return FaultModel(A, C, Bu=Bu, Bf=Bf)


YUAN_WEAK = np.array([
    [0, 0, 0, 1, 0, 0, 1, 1], [0, 1, 1, 0, 1, 1, 1, 0], [0, 1, 1, 1, 1, 1, 0, 1], [0, 1, 1, 1, 1, 1, 1, 1],
    [1, 0, 1, 0, 1, 1, 1, 0], [1, 0, 1, 1, 1, 1, 0, 1], [1, 0, 1, 1, 1, 1, 1, 1], [1, 1, 0, 0, 1, 1, 0, 0],
    [1, 1, 0, 1, 1, 1, 1, 1], [1, 1, 1, 0, 0, 1, 1, 0], [1, 1, 1, 0, 1, 0, 1, 0], [1, 1, 1, 0, 1, 1, 1, 0],
    [1, 1, 1, 1, 0, 1, 0, 1], [1, 1, 1, 1, 0, 1, 1, 1], [1, 1, 1, 1, 1, 0, 0, 1], [1, 1, 1, 1, 1, 0, 1, 1],
    [1, 1, 1, 1, 1, 1, 0, 1], [1, 1, 1, 1, 1, 1, 1, 1]], dtype=bool)

YUAN_STRONG = np.array([
    [0, 0, 0, 1, 0, 0, 1, 1], [0, 1, 1, 0, 1, 1, 1, 0], [0, 1, 1, 1, 1, 1, 0, 1], [0, 1, 1, 1, 1, 1, 1, 1],
    [1, 0, 1, 0, 1, 1, 1, 0], [1, 0, 1, 1, 1, 1, 0, 1], [1, 0, 1, 1, 1, 1, 1, 1], [1, 1, 0, 0, 1, 1, 0, 0],
    [1, 1, 0, 1, 1, 1, 1, 1], [1, 1, 1, 0, 1, 1, 1, 0], [1, 1, 1, 1, 1, 1, 0, 1], [1, 1, 1, 1, 1, 1, 1, 1]],
    dtype=bool)


def example_5_4():
    """Varga (2017), Example 5.4: Gu = [(s+1)/(s−2); (s+2)/(s−3)], Gd = [(s−1)/(s+2); 0], Gf = [Gu [0; 1]]."""
    return FaultModel([[2.0, 0, 0], [0, 3.0, 0], [0, 0, -2.0]], [[3.0, 0, -3.0], [0, 5.0, 0]],
                      Bu=[[1.0], [1.0], [0.0]], Bd=[[0.0], [0.0], [1.0]], Du=[[1.0], [1.0]], Dd=[[1.0], [0.0]],
                      Bf=[[1.0, 0.0], [1.0, 0.0], [0.0, 0.0]], Df=[[1.0, 0.0], [1.0, 1.0]])


def example_5_2():
    """Varga (2017), Example 5.2 (no solution): Gu = [(s+1)/(s+2); (s+2)/(s+3)], Gd = [1/(s+2); 0],
    Gf = [(s+1)/(s+2) 0; 0 1]."""
    # states: x1 (s+2) shared by Gu1, Gd1, Gf11 through separate states; x2 (s+3)
    A = np.diag([-2.0, -3.0, -2.0, -2.0])
    return FaultModel(A, [[-1.0, 0, 1.0, -1.0], [0, -1.0, 0, 0]], Bu=[[1.0], [1.0], [0], [0]],
                      Bd=[[0], [0], [1.0], [0]], Du=[[1.0], [1.0]],
                      Bf=[[0, 0], [0, 0], [0, 0], [1.0, 0]], Df=[[1.0, 0], [0, 1.0]])


def niemann():
    """Niemann (1998): n = 5, two controls, one disturbance, two actuator faults (Bf = Bu), full state output."""
    a = 1000 * np.array([
        [-0.0782, 0.2939, 0.0220, 0.0208, -0.0291], [0.0077, -0.0278, 0.0015, -0.0015, 0.0026],
        [-1.3251, 5.32608, -0.5263, 0.2214, -0.4777], [1.0809, -4.4452, 0.3770, -0.4631, 0.4032],
        [2.1532, -8.6386, 0.7811, -0.5745, 0.7816]])
    bd = 1000 * np.array([[0.0443], [-0.0042], [0.7910], [-0.6598], [-1.2881]])
    bu = np.array([[-0.007197, 0.003005], [0.003473, 0.000284], [1.218502, -0.032866], [1.322502, 0.020147],
                   [-0.082265, 0.024388]])
    return FaultModel(a, np.eye(5), Bu=bu, Bd=bd, Bf=bu)


def xiong_saif_1():
    """Xiong and Saif (2000), Example 1: n = 4, two controls, two disturbances, two faults."""
    a = np.array([[-9.9477, -0.7476, 0.2632, -5.0337], [52.1659, 2.7452, 5.5532, -24.4221],
                  [26.0922, 2.6361, -4.1975, -19.2774], [0.0, 0.0, 1.0, 0.0]])
    bu = np.array([[0.4422, 0.1761], [3.5446, -7.5922], [-5.52, 4.49], [0.0, 0.0]])
    bd = np.array([[0, 0], [0, 1.0], [1.0, 0], [0, 0]])
    bf = np.c_[bu[:, 0], np.zeros(4)]
    c = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 1, 1, 1]])
    df = np.c_[np.zeros(4), [0, 0, 1.0, 0]]
    return FaultModel(a, c, Bu=bu, Bd=bd, Bf=bf, Df=df)


def random_plant(seed: int, n: int, p: int, mu: int, md: int, mf: int, dt=None):
    """A random stable plant with feedthrough (the reference's ``rss``), from a seed."""
    rng = np.random.default_rng(seed)
    Q = np.linalg.qr(rng.standard_normal((n, n)))[0] if n else np.zeros((0, 0))
    A = Q @ np.diag(-rng.uniform(0.5, 3.0, n)) @ Q.T if n else np.zeros((0, 0))
    if dt is not None and n:
        A = Q @ np.diag(rng.uniform(-0.8, 0.8, n)) @ Q.T
    m = mu + md + mf
    B, C, D = rng.standard_normal((n, m)), rng.standard_normal((p, n)), rng.standard_normal((p, m))
    return FaultModel(A, C, Bu=B[:, :mu], Bd=B[:, mu:mu + md], Bf=B[:, mu + md:], Du=D[:, :mu],
                      Dd=D[:, mu:mu + md], Df=D[:, mu + md:], dt=dt, outputs=[f"y{i}" for i in range(p)])


def response(model: FaultModel, group: str, lam: complex) -> np.ndarray:
    """Transfer matrix of the inputs of ``group`` at ``λ`` (any FaultModel, e.g. an internal form)."""
    cols = [i for i, name in enumerate(n for g in ("u", "d", "f", "w") for n in model.inputs[g])
            if name in model.inputs[group]]
    B, D = model.B[:, cols], model.D[:, cols]
    if not model.n:
        return D.astype(complex)
    return D + model.C @ np.linalg.solve(lam * np.eye(model.n) - model.A, B)


def low_pass():
    """Rf = (s+1)/(s+2), Rw = 1/(s+2) (zero of Rw at infinity)."""
    return FaultModel([[-2.0]], [[1.0]], Bf=[[-1.0]], Df=[[1.0]], Bw=[[1.0]], faults=["f"])


def high_pass():
    """Rf = (s+1)/(s+2), Rw = s/(s+2) (zero of Rw at 0)."""
    return FaultModel([[-2.0]], [[1.0]], Bf=[[-1.0]], Df=[[1.0]], Bw=[[-2.0]], Dw=[[1.0]], faults=["f"])


def xiong_saif_2():
    """Xiong and Saif (2000), Example 2 (test_emmsyn.jl): n = 5, three controls, two disturbances, two faults."""
    a = np.array([[0, 0, -0.0034, 0, 0], [0, -0.041, 0.0013, 0, 0], [0, 0, -1.1471, 0, 0], [0, 0, -0.0036, 0, 0],
                  [0, 0.094, 0.0057, 0, -0.051]])
    bu = np.array([[-1.0, 0, 0], [0, 0, 0], [0, 0, 0.948], [0.916, -1, 0], [-0.598, 0, 0]])
    bd = np.array([[0, 1.0], [0.062, -0.132], [0, -7.189], [0, 0], [0, 0]])
    c = np.array([[1.0, 0, 0, 0, 0], [0, 0, 1, 0, 0], [0, 0, 0, 1, 0]])
    return FaultModel(a, c, Bu=bu, Bd=bd, Bf=bu[:, :2])


def example_5_13():
    """Varga (2017), Example 5.13: Gu = [s/(s²+3s+2) 1/(s+2); s/(s+1) 0; 0 1/(s+2)], actuator faults Gf = Gu."""
    # states: x1 = 1/(s+1), x2 = 1/(s+2) of input 1; x3 = 1/(s+2) of input 2
    # s/((s+1)(s+2)) = 2/(s+2) − 1/(s+1); s/(s+1) = 1 − 1/(s+1)
    A = np.diag([-1.0, -2.0, -2.0])
    B = np.array([[1.0, 0], [1.0, 0], [0, 1.0]])
    C = np.array([[-1.0, 2.0, 1.0], [-1.0, 0, 0], [0, 0, 1.0]])
    D = np.array([[0, 0], [1.0, 0], [0, 0]])
    return FaultModel(A, C, Bu=B, Du=D, Bf=B, Df=D)
