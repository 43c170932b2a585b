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
     |     +------> [drive cascade] -----+       current loops)
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
:func:`servotune.drive.cascade_response` gives it), so that a continuation can ask for it at
every corrector step. A digital drive is the sampled-data system it is
(:class:`SampledPadReceptance`): its receptance is the fundamental of the sampled-data response.

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

from ..cache import cached_njit
from ..drive import Drive
from ..structure.model import ModalModel, signal_name

__all__ = ["PadReceptance", "SampledPadReceptance", "pad_receptance"]


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

    Notes
    -----
    Made by :func:`pad_receptance`; calling it with angular frequencies [rad/s] returns
    ``G[o, i, k]`` [m/N], shape (n + 1, n + 1, K). ``n_pads`` is the number of pads n.
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
        object.__setattr__(self, "_shapes",
                           np.ascontiguousarray(shapes.reshape(-1, self._left.shape[1])))
        empty = np.zeros(1)
        if self.drive is None:
            drive = (False, empty, empty, empty, empty, empty, empty, np.zeros(5), np.zeros(4))
        else:
            (ci_n, ci_d), (f_n, f_d), (cv_n, cv_d), delays = self._cascade
            m = self.drive.motor
            motor = np.array([m.inductance, m.resistance,
                              m.torque_constant * m.back_emf_constant,
                              self.drive.kv / self.drive.ratio])
            drive = (True, ci_n, ci_d, f_n, f_d, cv_n, cv_d, np.array(delays, dtype=float),
                     motor)
        object.__setattr__(self, "_kernel_drive", drive)

    @property
    def n_pads(self) -> int:
        return len(self.pads)

    def __call__(self, omega) -> np.ndarray:
        """The receptance at angular frequencies ``omega`` [rad/s] (> 0).

        Parameters
        ----------
        omega : array_like, shape (K,)
            Angular frequencies [rad/s], finite and > 0 (a scalar counts as K = 1).

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
        n = self.n_pads + 1
        out = np.empty((n, n, omega.size), dtype=complex)
        _receptance_kernel(omega, self._omega2, self._damping, self._shapes,
                           self._right.shape[0], n, *self._kernel_drive, out)
        return out


@cached_njit
def _polynomial(c, s):
    out = c[0] + 0j
    for i in range(1, c.size):
        out = out * s + c[i]
    return out


@cached_njit
def _receptance_kernel(omega, omega2, damping, shapes, n_right, n, has_drive, ci_n, ci_d,
                       f_n, f_d, cv_n, cv_d, delays, motor, out):
    """Modal sum between the ports, then the torque closed through the motor port (rows:
    outputs 0..n-1, rel n, feedback n+1; columns: inputs 0..n-1, rel torque n)."""
    rows = shapes.shape[0] // n_right
    h = np.empty((rows, n_right), dtype=np.complex128)
    for k in range(omega.size):
        w = omega[k]
        h[:, :] = 0.0
        for m in range(omega2.size):
            term = 1.0 / (omega2[m] - w * w + 1j * w * damping[m])
            for o in range(rows):
                for i in range(n_right):
                    h[o, i] += shapes[o * n_right + i, m] * term
        if not has_drive:
            for o in range(n):
                for i in range(n):
                    out[o, i, k] = h[o, i]
            continue
        s = 1j * w
        t_i, t_v, t_m, t_p, t_f = delays[0], delays[1], delays[2], delays[3], delays[4]
        inductance, resistance, ktke, kv_per_ratio = motor[0], motor[1], motor[2], motor[3]
        ci = _polynomial(ci_n, s) / _polynomial(ci_d, s) * np.exp(-s * t_i)
        winding = s * inductance + resistance + ci
        a = ci * _polynomial(f_n, s) / _polynomial(f_d, s) * np.exp(-s * t_v) * \
            _polynomial(cv_n, s) / _polynomial(cv_d, s)
        measurement = np.exp(-s * t_m) / (1.0 + s * t_f)
        g_fb = -(a * np.exp(-s * t_p) * kv_per_ratio) / winding
        g_rel = -(a * measurement + ktke) * s / winding
        loop_t = g_fb * h[n + 1, n] + g_rel * h[n, n]
        for i in range(n):
            torque = (g_fb * h[n + 1, i] + g_rel * h[n, i]) / (1.0 - loop_t)
            for o in range(n):
                out[o, i, k] = h[o, i] + h[o, n] * torque


def _cascade_polynomials(drive: Drive) -> tuple:
    """Numerators and denominators of the cascade's controllers and filters, and its delays."""
    def poly(tf):
        return (np.asarray(tf.num[0][0], dtype=float), np.asarray(tf.den[0][0], dtype=float))

    return (poly(drive.current_loop.transfer_function()), poly(drive.torque_filter()),
            poly(drive.velocity_loop.transfer_function()), (0.0, 0.0, 0.0, 0.0, 0.0))


class SampledPadReceptance:
    """The receptance of :class:`PadReceptance` with a digital drive: the fundamental of the
    sampled-data axis' response (:class:`servotune.digital.SampledAxis` with the pads free and
    their forces as inputs; the aliases the drive's holds add are left out, as in the
    compliance of the tuning: below 1e-6 of the fundamental on the bundled axis).

    Parameters
    ----------
    structure : ModalModel
        The structure with the pads free.
    drive : Drive
        A digital drive.
    pads : tuple of str
        The pad DOFs.
    force_dof, output_dof : str
        Work-piece DOFs of the force and of the displacement.
    """

    #: The table's range [Hz] and its points per decade (cubic splines of the real and
    #: imaginary parts in log frequency; outside it the receptance is evaluated directly).
    TABLE_HZ = (0.05, 3900.0)
    TABLE_PER_DECADE = 600

    def __init__(self, structure: ModalModel, drive: Drive, pads, force_dof: str,
                 output_dof: str):
        from ..digital import SampledAxis
        from ..plant import Contact

        self.pads, self.force_dof, self.output_dof, self.drive = (tuple(pads), force_dof,
                                                                  output_dof, drive)
        self._axis = SampledAxis(structure, drive, Contact.free(), self.pads, force_pads=True)
        self._inputs = [signal_name(p, "f_") for p in self.pads] + [signal_name(force_dof, "f_")]
        self._outputs = [signal_name(p) for p in self.pads] + [signal_name(output_dof)]
        self._table = None

    @property
    def n_pads(self) -> int:
        return len(self.pads)

    def exact(self, omega) -> np.ndarray:
        """Return the receptance evaluated directly (no table).

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s], > 0.

        Returns
        -------
        numpy.ndarray
            Complex, shape (n + 1, n + 1, K), as :meth:`__call__`.
        """
        return self._axis.response(np.atleast_1d(np.asarray(omega, dtype=float)),
                                   self._inputs, self._outputs)

    def _spline(self):
        if self._table is None:
            import scipy.interpolate

            lo, hi = (2 * np.pi * f for f in self.TABLE_HZ)
            hi = min(hi, 0.99 * self._axis.nyquist("velocity"))
            n = int(self.TABLE_PER_DECADE * np.log10(hi / lo)) + 1
            grid = np.geomspace(lo, hi, n)
            values = self.exact(grid)
            self._table = (lo, hi, scipy.interpolate.CubicSpline(np.log(grid), values,
                                                                 axis=-1))
        return self._table

    def __call__(self, omega) -> np.ndarray:
        """The receptance at angular frequencies ``omega`` [rad/s] (> 0), shape
        (n + 1, n + 1, K) as :meth:`PadReceptance.__call__`.

        Harmonic balance asks for it at many frequencies: it is tabulated once (600 points
        per decade over :attr:`TABLE_HZ`, below the speed controller's Nyquist frequency) and
        interpolated by cubic splines in log frequency (within 2e-6 of the direct evaluation
        on the bundled axis, tests/test_harmonic_balance.py); outside the table it is
        evaluated directly."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        if not np.all(np.isfinite(omega) & (omega > 0.0)):
            raise ValueError("the receptance is asked at finite frequencies > 0 rad/s")
        lo, hi, spline = self._spline()
        inside = (omega >= lo) & (omega <= hi)
        out = np.empty((self.n_pads + 1, self.n_pads + 1, omega.size), dtype=complex)
        if inside.any():
            out[:, :, inside] = spline(np.log(omega[inside]))
        if (~inside).any():
            out[:, :, ~inside] = self.exact(omega[~inside])
        return out


#: The sampled receptances made (their tables are the expensive part), a few kept.
_SAMPLED: dict = {}


def pad_receptance(structure: ModalModel, drive: Drive | None, pads, force_dof: str = "wp.x",
                   output_dof: str | None = None) -> PadReceptance | SampledPadReceptance:
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
        Work-piece DOF where the harmonic force acts (default ``"wp.x"``).
    output_dof : str, optional
        Work-piece DOF whose displacement is the compliance (default ``force_dof``).

    Returns
    -------
    PadReceptance
        G(j w) between the n pad forces and the work-piece force (inputs) and the n pad
        displacements and the work-piece displacement (outputs), [m/N].

    Raises
    ------
    ValueError
        If there is no pad, or the structure's damping couples its modes (``phi^T C phi`` not
        diagonal: harmonic balance here needs modal damping).
    servotune.structure.model.UnknownDofError
        (a ValueError and a KeyError) If a DOF is not in the structure.

    See Also
    --------
    servotune.frequency.port_compliance : the same coupling with a linear pad contact.
    """
    pads = tuple(pads)
    if not pads:
        raise ValueError("harmonic balance of the guide-way friction needs the pad DOFs")
    output_dof = force_dof if output_dof is None else output_dof
    if drive is not None and not drive.digital.is_continuous:
        key = (id(structure), drive, pads, force_dof, output_dof)
        kept = _SAMPLED.get(key)
        if kept is None or kept[0] is not structure:
            if len(_SAMPLED) >= 4:
                _SAMPLED.pop(next(iter(_SAMPLED)))
            kept = _SAMPLED[key] = (structure, SampledPadReceptance(structure, drive, pads,
                                                                    force_dof, output_dof))
        return kept[1]
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
