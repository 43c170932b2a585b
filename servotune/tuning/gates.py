"""The smooth gates of the tuning problem's design-dependent frequency conditions.

A condition that must hold only for ``w <= w_edge`` (or in a window), with the edge depending
on the design, is imposed at every grid frequency as ``value + sigma(kappa log(w / w_edge))
>= 0``, the value normalised to (-1, 1) and the logistic sigma switching the condition off
past the edge; the edges lie ``GATE_SAFETY`` beyond the requirement so that the gate's soft
part does not eat into it. In a model the condition does not apply to, the row is lifted by
``GATE_OFF`` and always holds.
"""

from __future__ import annotations

__all__ = ["GATE_SHARPNESS", "GATE_SAFETY", "GATE_OFF", "gate_switch"]

#: kappa of the logistic gates (per unit of log frequency): 5 % past an edge the gate is
#: 82 % open, 10 % past it 95 %.
GATE_SHARPNESS = 30.0
#: Edges of the gated constraints lie this factor beyond the requirement.
GATE_SAFETY = 1.15
#: What a gated row is lifted by where it does not apply (its value part is within (-1, 1)).
GATE_OFF = 2.0


def gate_switch(y):
    """Return the logistic gate ``1 / (1 + exp(-kappa y))`` of a casadi expression.

    Parameters
    ----------
    y : casadi.SX
        Log distance past the edge (``log(w / w_edge)``).

    Returns
    -------
    casadi.SX
        0 well before the edge, 1 well past it.
    """
    import casadi as ca

    return 1.0 / (1.0 + ca.exp(-GATE_SHARPNESS * y))
