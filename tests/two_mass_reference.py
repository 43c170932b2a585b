"""The closed forms of the paper's two-mass system (Bianchi et al., Procedia CIRP 21 (2014),
sec 4.1, Eq 1-7), written out for the tests independently of servotune.twomass.

Layout B: ground --C-- M1 --K-- M2 = alpha M1, force f2 on M2, output x2. Fig 5 uses
M1 = 5000 kg, K = 16e6 N/m, alpha = 0.3, for which the paper gives Copt = 4.912e5 N s/m.
"""

import math

import numpy as np

M1, K, ALPHA = 5000.0, 16e6, 0.3  # the paper's Fig 5
M2 = ALPHA * M1
COPT_PAPER = 4.912e5  # [N s/m], the paper's Fig 5


def c_opt(m1=M1, k=K, alpha=ALPHA):
    """Copt = sqrt(K M1) f(alpha), f = sqrt((3 r + a - 1) / (2 a (a + r))), r = sqrt(1 + a^2)."""
    r = math.sqrt(1 + alpha * alpha)
    return math.sqrt(k * m1) * math.sqrt((3 * r + alpha - 1) / (2 * alpha * (alpha + r)))


def g(alpha=ALPHA):
    """g(alpha) = (1 - alpha + sqrt(1 + alpha^2)) / alpha: the peak at Copt is g / K."""
    return (1 - alpha + math.sqrt(1 + alpha * alpha)) / alpha


def fixed_points(m1=M1, k=K, alpha=ALPHA):
    """w_f1,2 = w0 sqrt((1 + a -/+ sqrt(1 + a^2)) / (2 a)), w0 = sqrt(K / M1) [rad/s]."""
    w0, r = math.sqrt(k / m1), math.sqrt(1 + alpha * alpha)
    return (w0 * math.sqrt((1 + alpha - r) / (2 * alpha)),
            w0 * math.sqrt((1 + alpha + r) / (2 * alpha)))


def h(omega, c, m1=M1, k=K, alpha=ALPHA):
    """x2/f2 [m/N] at omega [rad/s] with guide-way damping c [N s/m]."""
    w = np.asarray(omega, dtype=float)
    return (k - m1 * w**2 + 1j * w * c) / (alpha * m1**2 * w**4 - (1 + alpha) * k * m1 * w**2
                                           + 1j * w * c * (k - alpha * m1 * w**2))
