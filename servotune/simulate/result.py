"""Results of a time simulation: histories, window energies with their balance, sweep envelopes.

Energy balance of the structure over a window [t0, t1] (all works done ON the structure)::

    W_force + W_motor + W_friction + W_damping = Delta (T + V)

    W_force    = int f_wp . v_wp dt                    (external force at the work piece)
    W_motor    = int T (omega_rotor - omega_stator) dt (motor torque)
    W_friction = - sum_pads int F_p v_p dt             (guide-way friction; < 0 = dissipated)
    W_damping  = - int v^T D v dt                      (distributed structural damping, <= 0)
    T + V      = 1/2 v^T M v + 1/2 x^T K x

The friction work splits into the change of the bristles' elastic energy sum sigma0_p z_p^2 / 2
and what the contact dissipates. The residual of the balance measures the accuracy of the
integration (the quadrature of the powers and the states are independent of each other).

The sweep envelope is the amplitude of the first harmonic of the response at the instantaneous
excitation frequency, fitted by least squares over each cycle of the force (with a local linear
trend, which removes the travel of a moving axis), divided by the force amplitude.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["SimulationResult", "SimulationError", "WindowEnergies", "SweepEnvelope",
           "WORK_CHANNELS"]

WORK_CHANNELS = ("force", "motor", "friction", "damping")


class SimulationError(RuntimeError):
    """The integration stopped before the end; ``.result`` holds what was computed, ``.time``
    the time reached [s]."""

    def __init__(self, message: str, result: SimulationResult | None = None,
                 time: float = math.nan):
        super().__init__(message)
        self.result = result
        self.time = time


@dataclass(frozen=True)
class WindowEnergies:
    """Works done on the structure over [t_start, t_end] and the energy balance [J].

    Parameters
    ----------
    t_start, t_end : float
        The window [s].
    force, motor, friction, damping : float
        Works [J] done on the structure by the work-piece force, the motor torque, the
        guide-way friction and the structural damping (see the module docstring).
    structure_change : float
        Change of the structure's kinetic plus potential energy, Delta(T + V) [J].
    bristle_change : float
        Change of the bristles' elastic energy, sum sigma0_p z_p^2 / 2 [J].
    """

    t_start: float
    t_end: float
    force: float
    motor: float
    friction: float
    damping: float
    structure_change: float
    bristle_change: float

    @property
    def residual(self) -> float:
        """W_force + W_motor + W_friction + W_damping - Delta(T + V) [J]."""
        return (self.force + self.motor + self.friction + self.damping
                - self.structure_change)

    @property
    def largest(self) -> float:
        """The largest magnitude among the terms of the balance [J]."""
        return max(abs(self.force), abs(self.motor), abs(self.friction), abs(self.damping),
                   abs(self.structure_change))

    @property
    def relative_residual(self) -> float:
        """|residual| / largest term."""
        return abs(self.residual) / self.largest if self.largest > 0 else 0.0

    @property
    def friction_dissipated(self) -> float:
        """Energy dissipated in the contacts: -W_friction - Delta(bristle energy) [J]."""
        return -self.friction - self.bristle_change

    def to_dict(self) -> dict:
        """Return the window's energies as JSON-ready data.

        Returns
        -------
        dict
            The window [s], the works and energy changes [J] under ``*_j`` names, the energy
            dissipated by friction, and the balance's residual and relative residual.
        """
        return {"t_start": self.t_start, "t_end": self.t_end, "energy_force_j": self.force,
                "energy_motor_j": self.motor, "energy_friction_j": self.friction,
                "energy_damping_j": self.damping,
                "energy_structure_change_j": self.structure_change,
                "energy_bristle_change_j": self.bristle_change,
                "friction_dissipated_j": self.friction_dissipated,
                "balance_residual_j": self.residual,
                "balance_relative_residual": self.relative_residual}


@dataclass(frozen=True)
class SweepEnvelope:
    """Response amplitude per unit force along a sine sweep.

    Attributes
    ----------
    frequency : numpy.ndarray
        Instantaneous excitation frequency at the middle of each cycle [rad/s].
    time : numpy.ndarray
        Middle of each cycle [s].
    amplitude : numpy.ndarray
        First-harmonic amplitude of the response per unit force amplitude [m/N].
    resonance : float
        Frequency of the largest amplitude [rad/s] (parabola through the top three cycles).
    peak : float
        The largest amplitude per unit force [m/N] (same refinement).
    """

    frequency: np.ndarray
    time: np.ndarray
    amplitude: np.ndarray
    resonance: float
    peak: float

    @property
    def resonance_hz(self) -> float:
        return self.resonance / (2.0 * math.pi)

    def plot(self, reference=None):
        """Plot the envelope against frequency (:func:`servotune.plots.plot_sweep_envelope`).

        Parameters
        ----------
        reference : dict, optional
            ``{label: (omega [rad/s], |compliance| [m/N])}`` linear curves drawn dashed.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        from .. import plots

        return plots.plot_sweep_envelope([self], reference=reference)


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """A simulated history (recorded every ``record_step``) and its energies (SI).

    Attributes
    ----------
    t : numpy.ndarray
        Record times [s], from 0.
    signals : dict
        Name -> array on ``t``: the plant outputs (``wp_x`` [m], ``slide_x`` [m],
        ``omega_motor`` [rad/s], ``following_error`` [m], ``torque`` [N m], ``current`` [A]),
        per pad ``<pad>`` (displacement [m]), ``v_<pad>`` [m/s], ``F_<pad>`` (friction force
        [N]), ``z_<pad>`` (bristle deflection [m], LuGre), and the inputs (``x_ref``,
        ``f_wp_x``, ...).
    work : numpy.ndarray
        (len(t), 4) cumulative works from t = 0 [J] of :data:`WORK_CHANNELS`.
    checkpoints : numpy.ndarray
        Times [s] where the structure's and the bristles' energies are known exactly.
    checkpoint_work, structure_energy, bristle_energy : numpy.ndarray
        Cumulative works (n, 4), T + V and sum sigma0 z^2/2 at the checkpoints [J].
    pads : tuple of str
    friction : str
        Name of the friction law.
    scenario : str
    sweep : tuple, SweepPlan or None
        (f_start_hz, f_end_hz, t_start, t_end, force amplitude [N]) of a linear force sweep,
        or the :class:`~servotune.simulate.scenario.SweepPlan` of a variable-rate one.
    stats : dict
        Integrator statistics (step, steps, substeps, Newton iterations, wall time, ...).
    complete : bool
        False for the partial result of a failed run.
    """

    t: np.ndarray
    signals: dict
    work: np.ndarray
    checkpoints: np.ndarray
    checkpoint_work: np.ndarray
    structure_energy: np.ndarray
    bristle_energy: np.ndarray
    pads: tuple
    friction: str
    scenario: str
    sweep: object = None
    stats: dict = field(default_factory=dict)
    complete: bool = True

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"no signal {name!r}; the result has {sorted(self.signals)}") from None

    def _checkpoint(self, t: float) -> int:
        i = int(np.argmin(np.abs(self.checkpoints - t)))
        if abs(self.checkpoints[i] - t) > 1e-9 * max(1.0, abs(t)):
            raise ValueError(
                f"t = {t} s is not an energy checkpoint; checkpoints are every "
                f"{np.diff(self.checkpoints[:2])[0] if self.checkpoints.size > 1 else 0:g} s up "
                f"to {self.checkpoints[-1]:g} s (pass window=(t0, t1) to simulate() to add "
                "others)")
        return i

    def energies(self, t_start: float, t_end: float) -> WindowEnergies:
        """Return the works and the energy balance over a window between two checkpoints.

        Parameters
        ----------
        t_start, t_end : float
            Start and end [s] of the window, each an energy checkpoint (within 1e-9 relative),
            ``t_end > t_start``.

        Returns
        -------
        WindowEnergies
            The works done on the structure, the changes of its energy and of the bristles'.

        Raises
        ------
        ValueError
            If ``t_end <= t_start`` or a time is not a checkpoint.
        """
        if not t_end > t_start:
            raise ValueError(f"the window must have t_end > t_start, got ({t_start}, {t_end})")
        i, j = self._checkpoint(t_start), self._checkpoint(t_end)
        w = self.checkpoint_work[j] - self.checkpoint_work[i]
        return WindowEnergies(
            t_start=float(self.checkpoints[i]), t_end=float(self.checkpoints[j]),
            force=float(w[0]), motor=float(w[1]), friction=float(w[2]), damping=float(w[3]),
            structure_change=float(self.structure_energy[j] - self.structure_energy[i]),
            bristle_change=float(self.bristle_energy[j] - self.bristle_energy[i]))

    def sweep_envelope(self, output: str = "wp_x", t_min: float = 0.0) -> SweepEnvelope:
        """Amplitude per unit force of ``output`` along the force sweep (see module docstring).

        Parameters
        ----------
        output : str
            Recorded signal (default the work-piece X displacement).
        t_min : float
            Ignore cycles that start before this time [s] (the initial transient).

        Returns
        -------
        SweepEnvelope
            One point per force cycle from ``t_min`` on; the resonance and peak refined by a
            parabola through the largest point and its neighbours when that has a maximum
            within their spacing.

        Raises
        ------
        ValueError
            If the scenario was not a sweep, too few samples (fewer than 8) were recorded in a
            cycle, or no complete cycle starts after ``t_min``.
        KeyError
            If ``output`` is not a recorded signal.
        """
        if self.sweep is None:
            raise ValueError("the scenario has no force sweep (use scenario.sine_sweep)")
        y = self[output]
        t = self.t
        plan = self.sweep if hasattr(self.sweep, "cycle_times") else None
        if plan is not None:
            amp = plan.amplitude
            t_last = min(float(plan.t[-1]), t[-1])
            tk = plan.cycle_times(t_last)
        else:
            f0, f1, ts, te, amp = self.sweep
            rate = (f1 - f0) / (te - ts)
            # cycle boundaries: phase = 2 pi k
            t_last = min(te, t[-1])
            phase_end = f0 * (t_last - ts) + 0.5 * rate * (t_last - ts) ** 2
            k = np.arange(0, math.floor(phase_end) + 1)
            if rate != 0:
                tk = ts + (-f0 + np.sqrt(f0 * f0 + 2 * rate * k)) / rate
            else:
                tk = ts + k / f0
        idx = np.searchsorted(t, tk)
        freq, tm, amps = [], [], []
        for a, b, ta, tb in zip(idx[:-1], idx[1:], tk[:-1], tk[1:], strict=True):
            if ta < t_min:
                continue
            if b - a < 8:
                raise ValueError(f"only {b - a} samples in the cycle at {ta:.3f} s; record "
                                 "more densely (record_step)")
            tt = t[a:b]
            mid = 0.5 * (ta + tb)
            if plan is not None:
                ph = plan.phase_at(tt)
                f_mid = float(plan.frequency_at(mid))
            else:
                ph = 2 * math.pi * (f0 * (tt - ts) + 0.5 * rate * (tt - ts) ** 2)
                f_mid = f0 + rate * (mid - ts)
            basis = np.column_stack([np.ones_like(tt), tt - mid, np.cos(ph), np.sin(ph)])
            coef = np.linalg.lstsq(basis, y[a:b], rcond=None)[0]
            freq.append(2 * math.pi * f_mid)
            tm.append(mid)
            amps.append(math.hypot(coef[2], coef[3]) / amp)
        freq, tm, amps = np.array(freq), np.array(tm), np.array(amps)
        if amps.size == 0:
            raise ValueError("no complete sweep cycle after t_min")
        i = int(np.argmax(amps))
        res, peak = float(freq[i]), float(amps[i])
        if 0 < i < amps.size - 1:
            x, yy = freq[i - 1:i + 2], amps[i - 1:i + 2]
            c2, c1, c0 = np.polyfit(x - x[1], yy, 2)
            if c2 < 0:
                dx = -c1 / (2 * c2)
                if abs(dx) <= max(abs(x[2] - x[1]), abs(x[1] - x[0])):
                    res, peak = float(x[1] + dx), float(c0 - c1 * c1 / (4 * c2))
        return SweepEnvelope(frequency=freq, time=tm, amplitude=amps, resonance=res, peak=peak)

    def plot(self, kind: str = "envelope", pad: str | None = None):
        """Return a figure of the result.

        Parameters
        ----------
        kind : {"envelope", "energies", "hysteresis"}
            The sweep envelope of ``wp_x``, the cumulative works, or the friction force
            against the displacement of a pad.
        pad : str, optional
            The pad of the hysteresis figure; default the first.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.

        Raises
        ------
        ValueError
            If ``kind`` is unknown, or (``"envelope"``) the scenario was not a sweep.
        """
        from .. import plots

        if kind == "envelope":
            return plots.plot_sweep_envelope([self.sweep_envelope()], labels=[self.scenario])
        if kind == "energies":
            return plots.plot_energies(self)
        if kind == "hysteresis":
            return plots.plot_pad_hysteresis(self, pad or self.pads[0])
        raise ValueError(f"kind must be 'envelope', 'energies' or 'hysteresis', got {kind!r}")
