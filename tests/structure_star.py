"""A symmetric test structure with known repeated eigenvalues: a hub with identical arms.

A hub mass (DOF ``hub.x``, on a spring to ground) carries ``n_arms`` identical arms, each a
chain of ``n_per_arm`` equal masses m on equal springs k, the first spring attached to the hub.
With the hub held (the fixed-interface problem of a reduction to the hub) every arm is a
fixed-free chain, so each eigenvalue has multiplicity n_arms:

    omega_j = 2 sqrt(k/m) sin((2j - 1) pi / (2 (2n + 1))),  j = 1..n  (n = n_per_arm)

In the full model the n_arms - 1 combinations of arms that leave the hub still keep exactly
those frequencies (multiplicity n_arms - 1); the in-phase combination couples to the hub.
"""

import numpy as np
import scipy.sparse as sp

# k/m chosen so that the first arm frequency is about 10 Hz with 200 masses per arm
M_ARM, K_ARM = 1.0, 6.43e7
M_HUB, K_HUB = 50.0, 1e8


def star(n_arms=8, n_per_arm=200):
    """Sparse M, K and DOF names (``hub.x``, ``arm<a>.<j>``) of the star."""
    n = 1 + n_arms * n_per_arm
    rows, cols, vals = [], [], []

    def spring(i, j, value):
        rows.extend([i, j, i, j])
        cols.extend([i, j, j, i])
        vals.extend([value, value, -value, -value])

    for a in range(n_arms):
        first = 1 + a * n_per_arm
        spring(0, first, K_ARM)
        for j in range(n_per_arm - 1):
            spring(first + j, first + j + 1, K_ARM)
    stiffness = sp.coo_array((vals, (rows, cols)), shape=(n, n)).tocsr()
    stiffness = (stiffness + sp.diags_array(np.r_[K_HUB, np.zeros(n - 1)])).tocsr()
    mass = sp.diags_array(np.r_[M_HUB, np.full(n - 1, M_ARM)]).tocsr()
    dofs = ["hub.x"] + [f"arm{a}.{j}" for a in range(n_arms) for j in range(n_per_arm)]
    return mass, stiffness, dofs


def arm_frequencies(n_per_arm=200, count=5):
    """The fixed-free chain frequencies [rad/s] of one arm (each n_arms times repeated)."""
    j = np.arange(1, count + 1)
    return 2 * np.sqrt(K_ARM / M_ARM) * np.sin((2 * j - 1) * np.pi / (2 * (2 * n_per_arm + 1)))
