"""Interconnection of linear state-space blocks by signal name, by block algebra.

python-control's ``interconnect`` works for any (nonlinear) I/O system and linearises the
result numerically, which costs tens of milliseconds for the axis' few dozen blocks; for linear
blocks the closed form is exact and takes microseconds. Every block is a
:class:`control.StateSpace` with named inputs, outputs and states; a signal is produced by one
block output and consumed by any block inputs of the same name. With all blocks stacked,

    dx/dt = A x + B u,    y = C x + D u,    u = M y + N w

(M routes produced signals to the inputs that consume them, N the external inputs w), the
outputs solve ``y = (I - D M)^-1 (C x + D N w)`` (an algebraic loop is fine while
I - D M is regular), so that

    A_cl = A + B M L C,   B_cl = B (I + M L D) N,   C_cl = S L C,   D_cl = S L D N

with L = (I - D M)^-1 and S the rows of the requested outputs. States keep python-control's
names ``<block>_<state>``.

References
----------
K. J. Astrom, R. M. Murray, Feedback Systems, 2nd ed. (2021), sec 6.4 (block diagram algebra
of state-space systems).
"""

from __future__ import annotations

import control
import numpy as np

__all__ = ["connect"]


def connect(blocks, inputs, outputs, name: str = "sys",
            input_names=None, output_names=None) -> control.StateSpace:
    """Return the interconnection of linear blocks with the given external inputs and outputs.

    A block input is fed by the block output of the same name, else by the external input of
    that name, else it is left at zero.

    Parameters
    ----------
    blocks : sequence of control.StateSpace
        Linear blocks with named signals and a ``name``.
    inputs : sequence of str
        External input signals (consumed by blocks; an input no block consumes is kept with a
        zero column).
    outputs : sequence of str
        Signals produced by blocks, in the order of the result's outputs.
    name : str
        Name of the result; its states are ``<block name>_<state>``.
    input_names, output_names : sequence of str, optional
        Labels of the result's inputs and outputs (default the signal names).

    Returns
    -------
    control.StateSpace
        The closed interconnection: the blocks' states, the external inputs, the outputs.

    Raises
    ------
    ValueError
        A signal produced by two blocks, an output no block produces, or an algebraic loop
        without a solution.

    Examples
    --------
    A plant 1/(s + 1) under unit feedback: the closed loop 1/(s + 2).

    >>> g = control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]], inputs="u", outputs="y", name="g")
    >>> e = control.ss([], [], [], [[1.0, -1.0]], inputs=["r", "y"], outputs="u", name="e")
    >>> float(connect([g, e], ["r"], ["y"]).A[0, 0])
    -2.0
    """
    blocks = list(blocks)
    a_parts, b_parts, c_parts, d_parts = [], [], [], []
    states, in_labels, out_labels = [], [], []
    for blk in blocks:
        a_parts.append(np.asarray(blk.A, dtype=float).reshape(blk.nstates, blk.nstates))
        b_parts.append(np.asarray(blk.B, dtype=float).reshape(blk.nstates, blk.ninputs))
        c_parts.append(np.asarray(blk.C, dtype=float).reshape(blk.noutputs, blk.nstates))
        d_parts.append(np.asarray(blk.D, dtype=float).reshape(blk.noutputs, blk.ninputs))
        states += [f"{blk.name}_{s}" for s in blk.state_labels]
        in_labels += list(blk.input_labels)
        out_labels += list(blk.output_labels)
    from scipy.linalg import block_diag

    a = block_diag(*a_parts) if states else np.zeros((0, 0))
    b = _block(b_parts, len(states), len(in_labels))
    c = _block(c_parts, len(out_labels), len(states))
    d = _block(d_parts, len(out_labels), len(in_labels))
    produced = {}
    for j, sig in enumerate(out_labels):
        if sig in produced:
            raise ValueError(f"signal {sig!r} is produced by two blocks")
        produced[sig] = j
    m = np.zeros((len(in_labels), len(out_labels)))
    n = np.zeros((len(in_labels), len(inputs)))
    ext = {s: k for k, s in enumerate(inputs)}
    for i, sig in enumerate(in_labels):
        if sig in produced:
            m[i, produced[sig]] = 1.0
        elif sig in ext:
            n[i, ext[sig]] = 1.0
    missing = [s for s in outputs if s not in produced]
    if missing:
        raise ValueError(f"outputs {missing} are produced by no block")
    loop = np.eye(len(out_labels)) - d @ m
    try:
        lc = np.linalg.solve(loop, c)
        ld = np.linalg.solve(loop, d)
    except np.linalg.LinAlgError:
        raise ValueError("the interconnection has an algebraic loop without a solution") \
            from None
    rows = [produced[s] for s in outputs]
    a_cl = a + b @ m @ lc
    b_cl = b @ (n + m @ ld @ n)
    c_cl = lc[rows]
    d_cl = (ld @ n)[rows]
    return control.ss(a_cl, b_cl, c_cl, d_cl, inputs=list(input_names or inputs),
                      outputs=list(output_names or outputs), states=states, name=name)


def _block(parts, rows, cols):
    out = np.zeros((rows, cols))
    r = c = 0
    for p in parts:
        out[r:r + p.shape[0], c:c + p.shape[1]] = p
        r += p.shape[0]
        c += p.shape[1]
    return out
