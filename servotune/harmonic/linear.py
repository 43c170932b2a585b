"""The linear part of the closed-loop axis at the guide-way pads, for harmonic balance.

Harmonic balance of the axis needs the linear part (structure, drive cascade and motor) only as
a map from the forces that act on it to the motions that matter, at the harmonics k omega of the
excitation. Its inputs are the friction force of each pad (on the pad DOF) and the work-piece
force; its outputs the pad displacements and the work-piece displacement::

            f_1 .. f_n (pads), F (work piece)
                       |
     +-----------------v-----------------+
     |  structure (modal sum)  <---- T   |      T = g_fb(jw) x_fb + g_rel(jw) phi
     |     |  x_fb, phi                  |      (the cascade: position, velocity and
     |     +------> [drive cascade] -----+       current loops, exact delays)
     +-----------------+-----------------+
                       v
              x_1 .. x_n (pads), x_wp

With the structure's receptances between the ports (modal sum with mass-normalised modes,
``H(jw) = sum_r phi_r phi_r^T / (omega_r^2 - w^2 + j w d_r)``) and the torque closing through
the one motor port, the closed loop is a rank-one update of the open structure::

    T = g^T H_(fb,rel),u u / (1 - g^T h_(fb,rel),T),      x = H_o,u u + h_o,T T

This is the coupling of :func:`servotune.frequency.port_compliance` with the pads left free
(their friction is what harmonic balance supplies), evaluated cheaply at any frequency once the
modal data and the cascade's polynomials are set up (the cascade as
:func:`servotune.drive.cascade_response` gives it, with exact delays), so that a continuation
can ask for it at every corrector step.

References
----------
M. Krack, J. Gross, "Harmonic Balance for Nonlinear Vibration Problems", Springer (2019),
sec 3.4 (condensation to the nonlinear DOFs).
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 3.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..drive import Drive
from ..structure.model import ModalModel

__all__ = ["PadReceptance", "pad_receptance"]


@dataclass(frozen=True, eq=False)
class PadReceptance:
    """Closed-loop receptance of the axis between its pads and the work piece (SI).

    Attributes
    ----------
    pads : tuple of str
        The pad DOFs (their friction forces are inputs 0..n-1, their displacements outputs
        0..n-1).
    force_dof, output_dof : str
        Work-piece DOF of the force (input n) and of the displacement (output n).
    drive : Drive or None
        The cascade closed through the motor port (None: the structure alone).
    """

    pads: tuple
    force_dof: str
    output_dof: str
    drive: Drive | None
    _omega2: np.ndarray = field(repr=False)
    _damping: np.ndarray = field(repr=False)
    _left: np.ndarray = field(repr=False)    # (n_left, r): outputs, then rel, fb
    _right: np.ndarray = field(repr=False)   # (n_right, r): inputs, then rel
    _cascade: tuple = field(default=(), repr=False)

    def __post_init__(self) -> None:
        shapes = self._left[:, None, :] * self._right[None, :, :]
        object.__setattr__(self, "_shapes", shapes.reshape(-1, self._left.shape[1]))

    @property
    def n_pads(self) -> int:
        return len(self.pads)

    def __call__(self, omega) -> np.ndarray:
        """The receptance at angular frequencies ``omega`` [rad/s] (> 0).

        Parameters
        ----------
        omega : array_like, shape (K,)

        Returns
        -------
        numpy.ndarray, complex, shape (n + 1, n + 1, K)
            ``G[o, i, k]`` [m/N]: output o (pads, then the work piece) per input i (pad forces
            acting on the pad DOFs, then the work-piece force) at ``omega[k]``.

        Raises
        ------
        ValueError
            If a frequency is not finite and positive.
        """
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        if not np.all(np.isfinite(omega) & (omega > 0.0)):
            raise ValueError("the receptance is asked at finite frequencies > 0 rad/s")
        denom = self._omega2[:, None] - omega[None, :] ** 2 + 1j * omega[None, :] * \
            self._damping[:, None]
        pl, pr = self._left.shape[0], self._right.shape[0]
        h = (self._shapes @ (1.0 / denom)).reshape(pl, pr, omega.size)
        n = self.n_pads + 1
        if self.drive is None:
            return h[:n, :n]
        g_fb, g_rel = _cascade_gains(self.drive, self._cascade, 1j * omega)
        # rows: outputs (n), rel (n), fb (n + 1); columns: inputs (n), rel torque (n)
        loop_u = g_fb * h[n + 1, :n] + g_rel * h[n, :n]            # (n, K)
        loop_t = g_fb * h[n + 1, n] + g_rel * h[n, n]              # (K,)
        torque = loop_u / (1.0 - loop_t)                            # T per input
        return h[:n, :n] + h[:n, n][:, None, :] * torque[None, :, :]


def _cascade_polynomials(drive: Drive) -> tuple:
    """Numerators and denominators of the cascade's controllers and filters, and its delays."""
    def poly(tf):
        return (np.asarray(tf.num[0][0], dtype=float), np.asarray(tf.den[0][0], dtype=float))

    sampling = drive.digital
    return (poly(drive.current_loop.transfer_function()), poly(drive.torque_filter()),
            poly(drive.velocity_loop.transfer_function()),
            (sampling.current_delay, sampling.velocity_delay,
             sampling.speed_measurement_delay, sampling.position_delay, sampling.speed_filter))


def _horner(coefficients, s):
    """A polynomial (highest power first) at s."""
    out = np.full(s.shape, coefficients[0], dtype=complex)
    for c in coefficients[1:]:
        out = out * s + c
    return out


def _cascade_gains(drive: Drive, cascade: tuple, s: np.ndarray):
    """Motor torque per feedback position and per rotor angle, ``T = g_fb x_fb + g_rel phi``
    (no reference): the cascade of :func:`servotune.drive.cascade_response` with exact delays,
    ``T = -(a D_p Kv/r x_fb + (a M_v + kt ke) s phi) / (s L + R + C_i D_i)``,
    ``a = C_i D_i F D_v C_v``."""
    (ci_n, ci_d), (f_n, f_d), (cv_n, cv_d), (t_i, t_v, t_m, t_p, t_f) = cascade
    m = drive.motor
    ci = _horner(ci_n, s) / _horner(ci_d, s) * np.exp(-s * t_i)
    winding = s * m.inductance + m.resistance + ci
    a = ci * _horner(f_n, s) / _horner(f_d, s) * np.exp(-s * t_v) * \
        _horner(cv_n, s) / _horner(cv_d, s)
    measurement = np.exp(-s * t_m) / (1.0 + s * t_f)
    g_fb = -(a * np.exp(-s * t_p) * drive.kv / drive.ratio) / winding
    g_rel = -(a * measurement + m.torque_constant * m.back_emf_constant) * s / winding
    return g_fb, g_rel


def pad_receptance(structure: ModalModel, drive: Drive | None, pads, force_dof: str = "wp.x",
                   output_dof: str | None = None) -> PadReceptance:
    """Set up the closed-loop receptance between pads and work piece.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure with the pads free (the guide-way contact is not in it).
    drive : Drive or None
        The cascade (position, velocity and current loops) closed through the motor port;
        None for the structure without motion control.
    pads : sequence of str
        The pad DOFs (relative X at the guide-way pads).
    force_dof : str
        Work-piece DOF where the harmonic force acts.
    output_dof : str, optional
        Work-piece DOF whose displacement is the compliance (default ``force_dof``).

    Returns
    -------
    PadReceptance

    Raises
    ------
    ValueError
        If a DOF is not in the structure, or there is no pad, or the damping is not modal.

    See Also
    --------
    servotune.frequency.port_compliance : the same coupling with a linear pad contact.
    """
    pads = tuple(pads)
    if not pads:
        raise ValueError("harmonic balance of the guide-way friction needs the pad DOFs")
    output_dof = force_dof if output_dof is None else output_dof
    eye = np.eye(structure.n)

    def col(name):
        return eye[:, int(structure.index(name))]

    outputs = [col(p) for p in pads] + [col(output_dof)]
    inputs = [col(p) for p in pads] + [col(force_dof)]
    if drive is not None:
        m = drive.motor
        rel = col(m.rotor).copy()
        if m.stator:
            rel -= col(m.stator)
        fb = col(drive.encoder) if drive.feedback == "linear" else drive.ratio * rel
        outputs += [rel, fb]
        inputs += [rel]
    wr = structure.natural_frequencies()
    phi = structure.mode_shapes()
    modal_d = phi.T @ structure.damping @ phi
    off = modal_d - np.diag(np.diag(modal_d))
    if np.abs(off).max(initial=0.0) > 1e-9 * max(np.abs(modal_d).max(initial=0.0), 1e-300):
        raise ValueError("harmonic balance needs modal (proportional) structural damping; this "
                         "structure's damping couples its modes")
    left = np.array(outputs) @ phi
    right = np.array(inputs) @ phi
    return PadReceptance(pads=pads, force_dof=force_dof, output_dof=output_dof, drive=drive,
                         _omega2=wr * wr, _damping=np.ascontiguousarray(np.diag(modal_d)),
                         _left=left, _right=right,
                         _cascade=() if drive is None else _cascade_polynomials(drive))
