"""Tuning of guide-way damping and servo gains with casadi (the only casadi user).

The design variables are the guide-way damping C (axis total, shared by the pads), the position
gain Kv and the velocity PI (Kp, Ti); the user chooses which are free. Objectives are the peak
work-piece compliance over a band and the chatter margin; constraints are the sensitivity peaks
Ms of the velocity and position loops (gain and phase margins enter through the Ms disk:
Ms <= 1/(2 sin(PM/2)) guarantees PM, Ms <= GM/(GM - 1) guarantees GM), a minimum Kv, and bounds.

Frequency responses in real arithmetic
--------------------------------------
casadi has no complex numbers, and rebuilding the closed loop for every trial design would be
slow, so the responses are written at the *ports* of the structure (work piece, pads, motor,
encoder). With R(jw) the structure's receptance between the ports (modal sum, computed once),
pads of impedance z = (Z_0(jw) + j w C)/n (Z_0 the regime model's contact without its viscous
part, n the number of pads) couple in closed form::

    R_c = R - z R[:, p] (I + z R[p, p])^-1 R[p, :]  =  R - z sum_i a_i b_i^T / (1 + z lambda_i),

with the eigen-decomposition R[p, p] = U diag(lambda) U^-1 done once per frequency. The drive
then closes around the scalar port receptances (torque port e = rotor - stator, feedback port
f)::

    P_phi = e^T R_c e,  P_fb = f^T R_c e,  a = C_i F C_v,  b = kt ke,  den = j w L + R + C_i
    L_v   = a M_v j w P_phi / (den + b j w P_phi)                    (position loop open)
    L_p   = (Kv/r) D_p a P_fb / (den + (a M_v + b) j w P_phi)        (velocity loop closed)
    T/F   = -(a (Kv/r) D_p R_c[f, wp] + (a M_v + b) j w R_c[e, wp])
            / (den + a (Kv/r) D_p P_fb + (a M_v + b) j w P_phi)
    x/F   = R_c[wp, wp] + R_c[wp, e] T/F

with the digital drive's delays in C_i (current loop), F (velocity controller), M_v (speed
measurement and its filter) and D_p (position controller), all 1 in continuous time
(:func:`servotune.drive.cascade_response`).

Each complex quantity is carried as a (real, imaginary) pair of casadi expressions, so IPOPT
gets exact derivatives. The expressions are written once for ONE frequency, with the port data
of that frequency (R_ab, a_i b_i, lambda_i, C_i, F) as symbols, in the log-scaled variables
u = log(x / x0); casadi maps these kernels over the grids, whose port data are parameters of
the NLP. The symbolic work therefore does not grow with the grid, a refined grid costs only new
parameter values, and the exact Hessian of the Lagrangian is assembled from the kernels'
Hessians (summed over the frequencies with their multipliers). Peak and Ms constraints are
semi-infinite; they are imposed on a grid that is refined by exchange: after each solve the
true extrema are located on a fine grid, refined by bounded scalar search and added to the
grid, and the problem is re-solved warm (the multipliers of the old grid points carry over)
until the grid and the true values agree.

After solving, :func:`verify` checks the design independently with python-control on the
interconnected state-space plant (closed-loop poles, margins, Ms on a dense grid the optimiser
never saw, compliance peak, chatter limit). A design that fails verification is returned with
``success = False`` and the reasons, never as a success.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 4.1 (optimal guide-way damping), sec 5.2.
J. A. E. Andersson et al., "CasADi: a software framework for nonlinear optimization and
optimal control", Math. Prog. Comp. 11 (2019) 1-36.
R. Hettich, K. O. Kortanek, "Semi-infinite programming: theory, methods, and applications",
SIAM Review 35 (1993) 380-429 (exchange methods).
K. J. Astrom, R. M. Murray, Feedback Systems, 2nd ed. (2021), sec 13.3 (Ms and margins).
"""

from ..requirements import Requirements
from .ports import ResponseModel, evaluate
from .problem import (
    LOWPASS_VARIABLES,
    NOTCH_VARIABLES,
    ChatterTarget,
    Design,
    NoStableStartError,
    RequirementsNotMetError,
    TuningDidNotConvergeError,
    TuningProblem,
    expand_free,
)
from .solve import Prediction, TuningResult, TuningStatistics, tune
from .verify import ModelPerformance, Performance, RequirementCheck, requirement_checks, verify

__all__ = [
    "LOWPASS_VARIABLES",
    "NOTCH_VARIABLES",
    "ChatterTarget",
    "Design",
    "ModelPerformance",
    "NoStableStartError",
    "Performance",
    "Prediction",
    "RequirementCheck",
    "Requirements",
    "RequirementsNotMetError",
    "TuningDidNotConvergeError",
    "ResponseModel",
    "TuningProblem",
    "TuningResult",
    "TuningStatistics",
    "evaluate",
    "expand_free",
    "requirement_checks",
    "tune",
    "verify",
]
