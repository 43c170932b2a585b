"""The drive's controllers as the digital drive computes them: difference equations per rate.

A digital servo drive runs three controllers, each at its own sample period, each an integer
multiple of the fastest (the current controller's, T)::

    position   every N_p T:   omega_cmd = D_p [ Kv/r (x_ref - x_fb) + kvff/r v_ref ]
    velocity   every N_v T:   speed     = F_s(z) (phi_k - phi_{k-1}) / (N_v T)
                              T_set     = D_v [ C_v(z) (omega_cmd - speed) + J_ff/r a_ref ]
    current    every T:       u         = D_c [ C_i(z) (F_sp(z) T_set / kt - i) ]

Each controller samples its inputs at its instant kT', computes, and its output is applied
``d`` periods later (``D = z^-d``, the computation delay), then held until its next update
(zero-order hold): the motor voltage u is constant over every current period, the torque
set-point over every velocity period, the speed command over every position period. PI
controllers by forward Euler, ``u_k = Kp (e_k + (T'/Ti) sum_{j<k} e_j)``, i.e.
``C(z) = Kp (1 + T'/(Ti (z - 1)))``, or by Tustin, ``Kp (1 + T'/(2 Ti) (z + 1)/(z - 1))``. The
speed is the backward difference of the sampled rotor angle, smoothed by a first-order filter
``y_k = a y_{k-1} + (1 - a) x_k`` (``a = exp(-T'/tau)``, tau = ``speed_filter``). The current
set-point filters (second-order low-pass, notches) run in the current controller's cycle,
discretised by Tustin with the frequency prewarped to the filter's own.

:func:`digital_controller` turns a :class:`~servotune.drive.Drive` into a
:class:`DigitalController`: one discrete state space per rate (python-control systems with a
sample time), whose inputs are the sampled plant outputs, the references and the held outputs
of the slower controllers. The same matrices drive the time simulation
(:mod:`servotune.simulate`), the stability of the multi-rate loop
(:mod:`servotune.digital.sampled`) and, as transfer functions in z, the frequency responses of
the tuning.

References
----------
K. J. Astrom, B. Wittenmark, Computer-Controlled Systems, 3rd ed., Prentice Hall (1997),
sec 8.2-8.3 (discretised PI, Tustin with prewarping), sec 2.3 (computational delay).
G. Ellis, Control System Design Guide, 4th ed., Butterworth-Heinemann (2012), ch 4-5 (sample
rates, computation delay and the speed estimate of digital servo drives).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control
import numpy as np

from ..drive import Drive, PIController
from ..interconnect import connect

__all__ = ["ControllerLevel", "DigitalController", "digital_controller", "discrete_pi",
           "discrete_filter", "MEASURED", "REFERENCES"]

#: The plant outputs the controllers sample: winding current [A], rotor-minus-stator angle
#: [rad], position feedback [m].
MEASURED = ("current", "motor_angle", "x_fb")
#: The references the controllers read at their instants: position [m], velocity [m/s] and
#: acceleration [m/s^2].
REFERENCES = ("x_ref", "v_ref", "a_ref")


def _ss(sys: control.StateSpace, dt: float, inputs, outputs, name: str,
        states=None) -> control.StateSpace:
    """A python-control system rewrapped as discrete with sample time ``dt``."""
    n = sys.nstates
    return control.ss(sys.A, sys.B, sys.C, sys.D, dt, inputs=list(inputs),
                      outputs=list(outputs), name=name,
                      states=list(states) if states is not None else [f"x{i}" for i in
                                                                       range(n)])


def discrete_pi(pi: PIController, period: float, rule: str, inputs: str, outputs: str,
                name: str) -> control.StateSpace:
    """Return a PI controller as the drive computes it, a discrete state space.

    Parameters
    ----------
    pi : PIController
        Gain kp and integral time ti [s] (``ti = inf``: proportional only).
    period : float
        Sample period T [s].
    rule : {"forward_euler", "tustin"}
        Forward Euler: ``u_k = kp (e_k + (T/ti) sum_{j<k} e_j)``; Tustin: the integral by the
        trapezoidal rule, ``u_k = kp (e_k + (T/ti) (sum_{j<k} e_j + e_k / 2))``.
    inputs, outputs, name : str
        Signal and block names.

    Returns
    -------
    control.StateSpace
        Discrete (sample time ``period``); one state, the running sum of the errors
        ``S_k = sum_{j<k} e_j``, for a PI; none for a P controller.

    Examples
    --------
    Forward Euler: the first output is kp e_0, the integral acts from the next sample on.

    >>> pi = discrete_pi(PIController(2.0, 0.01), 1e-3, "forward_euler", "e", "u", "pi")
    >>> control.forced_response(pi, U=[1.0, 1.0, 1.0]).outputs.round(6).tolist()
    [2.0, 2.2, 2.4]
    """
    if rule not in ("forward_euler", "tustin"):
        raise ValueError(f"the integral rule must be 'forward_euler' or 'tustin', got {rule!r}")
    kp, ti = pi.kp, pi.ti
    if math.isinf(ti):
        return control.ss([], [], [], [[kp]], period, inputs=inputs, outputs=outputs,
                          name=name)
    ki = kp * period / ti
    d = kp + (0.5 * ki if rule == "tustin" else 0.0)
    return control.ss([[1.0]], [[1.0]], [[ki]], [[d]], period, inputs=inputs,
                      outputs=outputs, name=name, states=["sum"])


def discrete_filter(tf: control.TransferFunction, period: float, prewarp: float | None,
                    inputs: str, outputs: str, name: str) -> control.StateSpace:
    """Return a continuous filter discretised by Tustin, prewarped at ``prewarp`` [rad/s].

    Parameters
    ----------
    tf : control.TransferFunction
        The continuous filter (unit static gain).
    period : float
        Sample period [s].
    prewarp : float or None
        Frequency [rad/s] where the discrete filter matches the continuous one exactly (its
        corner or notch frequency); None: no prewarping.
    inputs, outputs, name : str
        Signal and block names.

    Returns
    -------
    control.StateSpace
        Discrete, sample time ``period``.

    Examples
    --------
    A notch keeps its depth at its own frequency after prewarping:

    >>> from servotune.drive import NotchFilter
    >>> n = NotchFilter(900.0, width=0.5, depth=0.1)
    >>> w = 2 * math.pi * 900.0
    >>> f = discrete_filter(n.transfer_function(), 125e-6, w, "a", "b", "notch")
    >>> round(abs(complex(f(np.exp(1j * w * 125e-6)))), 6)
    0.1
    """
    if prewarp is not None and prewarp * period >= math.pi:
        raise ValueError(f"the filter frequency {prewarp / (2 * math.pi):.4g} Hz is at or above "
                         f"half the sample rate ({0.5 / period:.4g} Hz): a drive cannot "
                         "compute it; lower it or sample faster")
    sys = control.sample_system(control.ss(tf), period, method="tustin",
                                prewarp_frequency=prewarp)
    return control.ss(sys.A, sys.B, sys.C, sys.D, period, inputs=inputs, outputs=outputs,
                      name=name)


@dataclass(frozen=True, eq=False)
class ControllerLevel:
    """One controller of the cascade at its own rate.

    Its input vector is the controller's global input vector g = [sampled plant outputs
    (:data:`MEASURED`), references (:data:`REFERENCES`), held outputs of every level]; at each
    of its instants it computes ``y = C x + D g`` (held until its next instant) and
    ``x <- A x + B g``.

    Attributes
    ----------
    name : str
        ``"position"``, ``"velocity"`` or ``"current"``.
    period : float
        Sample period [s].
    every : int
        Fast (current-controller) periods per update.
    system : control.StateSpace
        The controller with its own named inputs and outputs, sample time ``period``.
    a, b, c, d : numpy.ndarray
        Its matrices with B and D acting on the global input vector.
    output : str
        The held output (``omega_cmd``, ``torque_set``, ``voltage``).
    """

    name: str
    period: float
    every: int
    system: control.StateSpace
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d: np.ndarray
    output: str


@dataclass(frozen=True, eq=False)
class DigitalController:
    """The multi-rate controller of a digital drive: its levels, slow to fast.

    At a fast sample k, every level whose ``every`` divides k updates, slowest first (a
    faster level reads the output a slower one holds from this instant on); the motor voltage
    is then held until sample k + 1.

    Attributes
    ----------
    levels : tuple of ControllerLevel
        Position, velocity, current.
    period : float
        The fast (current-controller) period T [s].
    frame : int
        Fast periods of the slowest level (the period of the whole pattern).
    """

    levels: tuple[ControllerLevel, ...]
    period: float
    frame: int
    _tfs: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def n_measured(self) -> int:
        return len(MEASURED)

    @property
    def n_inputs(self) -> int:
        """Length of the global input vector g."""
        return len(MEASURED) + len(REFERENCES) + len(self.levels)

    @property
    def n_states(self) -> int:
        return sum(lv.a.shape[0] for lv in self.levels)

    def held_index(self, output: str) -> int:
        """Index of a level's held output in the global input vector.

        Parameters
        ----------
        output : str
            ``omega_cmd``, ``torque_set`` or ``voltage``.

        Returns
        -------
        int
        """
        names = [lv.output for lv in self.levels]
        return len(MEASURED) + len(REFERENCES) + names.index(output)

    def step(self, k: int, states: list, held: np.ndarray, measured: np.ndarray,
             references: np.ndarray) -> None:
        """Update the levels due at fast sample ``k`` in place (numpy; tests and scripts).

        Parameters
        ----------
        k : int
            The fast sample index.
        states : list of numpy.ndarray
            Each level's state, updated in place.
        held : numpy.ndarray
            The held outputs of the levels (one each), updated in place.
        measured : numpy.ndarray
            The sampled plant outputs at k (:data:`MEASURED`).
        references : numpy.ndarray
            The references at k (:data:`REFERENCES`).
        """
        for j, lv in enumerate(self.levels):
            if k % lv.every:
                continue
            g = np.concatenate([measured, references, held])
            held[j] = float((lv.c @ states[j] + lv.d @ g)[0])
            states[j][:] = lv.a @ states[j] + lv.b @ g

    def sample_maps(self, ad: np.ndarray, bd: np.ndarray, cy: np.ndarray,
                    br: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """Return the maps of the closed loop over one fast period, for each phase of the frame.

        The augmented state is ``xi = [plant (discretised), level states, held outputs]``;
        over the fast period starting at sample k (phase ``k mod frame``) it maps as
        ``xi_{k+1} = Phi_phase xi_k + Gamma_phase r_k`` (r the references).

        Parameters
        ----------
        ad, bd : numpy.ndarray
            The plant discretised with its voltage under zero-order hold over one fast period:
            ``x_{k+1} = ad x_k + bd u_k``.
        cy : numpy.ndarray
            Rows of the sampled outputs (:data:`MEASURED`) from the plant state (no
            feed-through: the plant is strictly proper from the held voltage).
        br : numpy.ndarray, optional
            Unused (kept for symmetry; references enter through Gamma).

        Returns
        -------
        list of (Phi, Gamma)
            One pair per phase 0 .. frame - 1.
        """
        n_p = ad.shape[0]
        sizes = [lv.a.shape[0] for lv in self.levels]
        offs = np.concatenate([[n_p], n_p + np.cumsum(sizes)]).astype(int)
        n_l = len(self.levels)
        n = int(offs[-1]) + n_l
        held0 = int(offs[-1])
        n_m, n_r = len(MEASURED), len(REFERENCES)
        v_idx = held0 + [lv.output for lv in self.levels].index("voltage")
        out = []
        for phase in range(self.frame):
            # g = G_x xi + G_r r, built up level by level (held outputs updated slow to fast)
            phi = np.eye(n)
            gam = np.zeros((n, n_r))
            g_x = np.zeros((n_m + n_r + n_l, n))
            g_r = np.zeros((n_m + n_r + n_l, n_r))
            g_x[:n_m, :n_p] = cy
            g_r[n_m:n_m + n_r] = np.eye(n_r)
            g_x[n_m + n_r:, held0:] = np.eye(n_l)
            for j, lv in enumerate(self.levels):
                if phase % lv.every:
                    continue
                s0, s1 = int(offs[j]), int(offs[j + 1])
                # new held output and state, in terms of xi (before this sample) and r
                y_x = lv.d @ g_x
                y_x[:, s0:s1] += lv.c
                y_r = lv.d @ g_r
                x_x = lv.b @ g_x
                x_x[:, s0:s1] += lv.a
                x_r = lv.b @ g_r
                phi[s0:s1] = x_x
                gam[s0:s1] = x_r
                phi[held0 + j] = y_x[0]
                gam[held0 + j] = y_r[0]
                # the faster levels read the new held output
                g_x[n_m + n_r + j] = y_x[0]
                g_r[n_m + n_r + j] = y_r[0]
            # plant over the period with the voltage held (as updated at this sample)
            plant_x = np.zeros((n_p, n))
            plant_x[:, :n_p] = ad
            plant_x += np.outer(bd[:, 0], phi[v_idx])
            plant_r = np.outer(bd[:, 0], gam[v_idx])
            phi[:n_p] = plant_x
            gam[:n_p] = plant_r
            out.append((phi, gam))
        return out

    def monodromy(self, ad: np.ndarray, bd: np.ndarray, cy: np.ndarray) -> np.ndarray:
        """Return the state transition of the closed loop over one frame (the slowest period).

        The multi-rate loop is periodic with the frame; it is stable when every eigenvalue of
        this matrix lies inside the unit circle (its lifted, time-invariant description over
        the frame).

        Parameters
        ----------
        ad, bd, cy : numpy.ndarray
            As :meth:`sample_maps`.

        Returns
        -------
        numpy.ndarray
            ``Phi_{frame-1} ... Phi_1 Phi_0``.
        """
        maps = self.sample_maps(ad, bd, cy)
        m = maps[0][0]
        for phi, _ in maps[1:]:
            m = phi @ m
        return m

    def level(self, name: str) -> ControllerLevel:
        """Return a level by name.

        Parameters
        ----------
        name : str
            ``"position"``, ``"velocity"`` or ``"current"``.

        Returns
        -------
        ControllerLevel
        """
        for lv in self.levels:
            if lv.name == name:
                return lv
        raise KeyError(name)

    def response(self, name: str, signal: str, z) -> np.ndarray:
        """Return a level's transfer from one of its inputs to its held output at ``z``.

        Parameters
        ----------
        name : str
            The level.
        signal : str
            One of its inputs (e.g. ``"motor_angle"`` of the velocity level).
        z : array_like of complex
            Points ``exp(j w T')`` of the level's own period T'.

        Returns
        -------
        numpy.ndarray
            ``C (z I - A)^-1 B + D`` for that input, shape of ``z``.
        """
        key = (name, signal)
        if key not in self._tfs:
            lv = self.level(name)
            sys = lv.system
            i = list(sys.input_labels).index(signal)
            n, n_in = sys.nstates, sys.ninputs
            a = np.asarray(sys.A, dtype=float).reshape(n, n)
            b = np.asarray(sys.B, dtype=float).reshape(n, n_in)[:, [i]]
            c = np.asarray(sys.C, dtype=float).reshape(sys.noutputs, n)[:1]
            d = float(np.asarray(sys.D, dtype=float).reshape(sys.noutputs, n_in)[0, i])
            # numerator and denominator of C (zI - A)^-1 B + D (levels have a few states)
            den = np.poly(a) if n else np.array([1.0])
            num = (np.poly(a - b @ c) - den + d * den) if n else np.array([d])
            self._tfs[key] = (num, den)
        num, den = self._tfs[key]
        z = np.asarray(z, dtype=complex)
        return np.polyval(num, z) / np.polyval(den, z)


def _delay(d: int, period: float, signal_in: str, signal_out: str, name: str):
    """z^-d as a shift register."""
    if d == 0:
        return control.ss([], [], [], [[1.0]], period, inputs=signal_in, outputs=signal_out,
                          name=name)
    a = np.diag(np.ones(d - 1), -1) if d > 1 else np.zeros((1, 1))
    b = np.zeros((d, 1))
    b[0, 0] = 1.0
    c = np.zeros((1, d))
    c[0, -1] = 1.0
    return control.ss(a, b, c, [[0.0]], period, inputs=signal_in, outputs=signal_out,
                      name=name, states=[f"r{i}" for i in range(d)])


def _gain(matrix, inputs, outputs, period, name):
    return control.ss([], [], [], np.atleast_2d(matrix), period, inputs=list(inputs),
                      outputs=list(outputs), name=name)


def _level(name: str, period: float, every: int, blocks, inputs, output: str,
           all_inputs) -> ControllerLevel:
    sys = connect(blocks, inputs, [output], name=name)
    sys = _ss(sys, period, inputs, [output], name, sys.state_labels)
    col = {s: i for i, s in enumerate(all_inputs)}
    n = sys.nstates
    b = np.zeros((n, len(all_inputs)))
    d = np.zeros((1, len(all_inputs)))
    sys_b = np.asarray(sys.B, dtype=float).reshape(n, len(inputs))
    sys_d = np.asarray(sys.D, dtype=float).reshape(1, len(inputs))
    for i, s in enumerate(inputs):
        b[:, col[s]] = sys_b[:, i]
        d[0, col[s]] = sys_d[0, i]
    return ControllerLevel(name, period, every, sys, np.asarray(sys.A, float).reshape(n, n),
                           b, np.asarray(sys.C, float).reshape(1, n), d, output)


def digital_controller(drive: Drive) -> DigitalController:
    """Return the drive's cascade as the digital drive computes it.

    Parameters
    ----------
    drive : Drive
        A drive whose :attr:`~servotune.drive.Drive.sampling` is digital (all three periods
        given; see :class:`~servotune.drive.Sampling`).

    Returns
    -------
    DigitalController
        Position, velocity and current levels (slow to fast).

    Raises
    ------
    ValueError
        A continuous drive, or periods that are not whole multiples of each other.

    Examples
    --------
    The default drive: current and speed controllers every 125 us, position every 1 ms.

    >>> from servotune.drive import Motor, PIController, Sampling
    >>> d = Drive(Motor(1.6, 1.6, 0.25, 4e-3), ratio=3.183e-3,
    ...           current_loop=PIController(20.0, 1e-3), velocity_loop=PIController(5.0, 0.02),
    ...           kv=25.0, sampling=Sampling())
    >>> [(lv.name, lv.every) for lv in digital_controller(d).levels]
    [('position', 8), ('velocity', 1), ('current', 1)]
    """
    s = drive.sampling
    if s is None or s.is_continuous:
        raise ValueError("digital_controller needs a sampled drive ([drive.sampling] with its "
                         "periods); this drive is continuous")
    n_v, n_p = s.multiples()
    t = s.current_period
    d = s.computation_delay
    r = drive.ratio
    m = drive.motor
    rule = s.integral_rule
    names = list(MEASURED) + list(REFERENCES) + ["omega_cmd", "torque_set", "voltage"]
    # position controller: omega_cmd = D_p (Kv/r (x_ref - x_fb) + kvff/r v_ref)
    tp = s.position_period
    pos = _level("position", tp, n_p * n_v, [
        _gain([[drive.kv / r, -drive.kv / r, drive.velocity_feedforward / r]],
              ["x_ref", "x_fb", "v_ref"], ["omega_raw"], tp, "position_gain"),
        _delay(d, tp, "omega_raw", "omega_cmd", "position_delay")],
        ["x_ref", "x_fb", "v_ref"], "omega_cmd", names)
    # velocity controller: speed from the angle difference, filter, PI, torque feed-forward
    tv = s.velocity_period
    blocks = [_gain([[1.0 / tv]], ["motor_angle"], ["angle_scaled"], tv, "speed_gain"),
              control.ss([[0.0]], [[1.0]], [[-1.0]], [[1.0]], tv, inputs="angle_scaled",
                         outputs="speed_raw", name="difference", states=["previous"])]
    measured = "speed_raw"
    if s.speed_filter > 0.0:
        a = math.exp(-tv / s.speed_filter)
        # y_k = a y_{k-1} + (1 - a) x_k with the state w_k = y_{k-1}
        blocks.append(control.ss([[a]], [[1.0 - a]], [[a]], [[1.0 - a]], tv,
                                 inputs="speed_raw", outputs="speed", name="speed_filter",
                                 states=["previous"]))
        measured = "speed"
    blocks += [_gain([[1.0, -1.0]], ["omega_cmd", measured], ["speed_error"], tv,
                     "speed_error"),
               discrete_pi(drive.velocity_loop, tv, rule, "speed_error", "torque_pi",
                           "velocity_pi"),
               _gain([[1.0, drive.torque_feedforward_inertia / r]], ["torque_pi", "a_ref"],
                     ["torque_raw"], tv, "torque_feedforward"),
               _delay(d, tv, "torque_raw", "torque_set", "velocity_delay")]
    vel = _level("velocity", tv, n_v, blocks, ["motor_angle", "omega_cmd", "a_ref"],
                 "torque_set", names)
    # current controller: set-point filters, current PI, delay
    blocks = []
    signal = "torque_set"
    for i, f in enumerate(drive.setpoint_filters):
        blocks.append(discrete_filter(f.transfer_function(), t, 2 * math.pi * f.f_hz, signal,
                                      f"setpoint_{i}", f"setpoint_filter_{i}"))
        signal = f"setpoint_{i}"
    blocks += [_gain([[1.0 / m.torque_constant, -1.0]], [signal, "current"], ["current_error"],
                     t, "current_error"),
               discrete_pi(drive.current_loop, t, rule, "current_error", "voltage_raw",
                           "current_pi"),
               _delay(d, t, "voltage_raw", "voltage", "current_delay")]
    cur = _level("current", t, 1, blocks, ["current", "torque_set"], "voltage", names)
    return DigitalController((pos, vel, cur), t, n_p * n_v)
