"""References of the Riccati and matrix-sign tests: SLICOT SB02PD's published example, the
Hamiltonian of eq 5.5, the spectral definition of sign(M) and random stabilizable problems."""
import numpy as np

# SLICOT SB02PD documentation example: A'X + XA − XGX + Q = 0 with G = diag(0, 1) = B R⁻¹ B'.
SB02PD_A = np.array([[0.0, 1.0], [0.0, 0.0]])
SB02PD_B = np.array([[0.0], [1.0]])
SB02PD_Q = np.diag([1.0, 2.0])
SB02PD_X = np.array([[2.0, 1.0], [1.0, 2.0]])


def _hamiltonian(A, G, Q):
    return np.block([[A, -G], [-Q, -A.T]])


def _sign_by_eig(M):
    w, V = np.linalg.eig(M)
    return ((V * np.sign(w.real)) @ np.linalg.inv(V)).real


def _random_problem(rng, nx=6, m=2, unstable=True):
    """Stabilizable (A, B) (B generic), Q ⪰ 0 with (Q, A) detectable, R ≻ 0."""
    A = rng.standard_normal((nx, nx))
    if not unstable:
        A -= (np.max(np.linalg.eigvals(A).real) + 0.5) * np.eye(nx)
    B = rng.standard_normal((nx, m))
    C = rng.standard_normal((nx, nx))
    Q = C @ C.T
    L = rng.standard_normal((m, m))
    R = L @ L.T + m * np.eye(m)
    return A, B, Q, R
