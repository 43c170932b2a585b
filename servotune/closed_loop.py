"""The controlled axis, whatever its drive: one interface for the continuous and the sampled one.

:func:`closed_loop` returns the model every check of a design uses: for the paper's continuous
drive (or no drive) a :class:`ContinuousAxis` over the python-control plant of
:func:`servotune.plant.build_plant`; for a digital drive the sampled-data
:class:`servotune.digital.SampledAxis`. Both answer the same questions: is the loop stable,
the loop transfer functions and their analyses, the work-piece compliance.
"""

from __future__ import annotations

import math

import control
import numpy as np

from . import frequency
from .digital import SampledAxis
from .drive import Drive
from .plant import Contact, build_plant, loop_transfer
from .structure.model import ModalModel, signal_name

__all__ = ["ContinuousAxis", "axis_compliance", "closed_loop"]


class ContinuousAxis:
    """The axis with a continuous drive (or none) as one python-control system.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    drive : Drive or None
        A continuous drive, or None for the structure with its contacts only.
    contact : Contact, optional
        The guide-way contact (default: free).
    pads : sequence of str
        The pad DOFs where the contact acts.
    """

    def __init__(self, structure: ModalModel, drive: Drive | None,
                 contact: Contact | None = None, pads=()):
        self.structure, self.drive, self.contact = structure, drive, contact
        self.pads = tuple(pads)
        self.plant = build_plant(structure, drive, contact, pads)

    def is_stable(self) -> bool:
        """Return whether the closed loop is stable (its poles).

        Returns
        -------
        bool
        """
        return frequency.is_stable(self.plant)

    def require_stable(self, what: str = "closed-loop axis") -> None:
        """Raise :class:`~servotune.plant.UnstableLoopError` when the loop is unstable.

        Parameters
        ----------
        what : str
            What the loop is, for the message.
        """
        frequency.require_stable(self.plant, what=what)

    def _loop(self, loop: str) -> control.StateSpace:
        return loop_transfer(self.structure, self.drive, self.contact, self.pads, loop)

    def nyquist(self, loop: str) -> float:
        """Return ``inf``: a continuous loop has no Nyquist frequency.

        Parameters
        ----------
        loop : {"velocity", "position"}

        Returns
        -------
        float
        """
        return math.inf

    def loop_response(self, loop: str, omega) -> np.ndarray:
        """Return L(j w) of the velocity loop (position loop open) or the position loop.

        Parameters
        ----------
        loop : {"velocity", "position"}
        omega : array_like
            Angular frequencies [rad/s].

        Returns
        -------
        numpy.ndarray
            Complex, shape of ``omega``.
        """
        return frequency.fast_frequency_response(self._loop(loop), omega).complex.reshape(-1)

    def analyse_loop(self, loop: str, omega=None) -> frequency.LoopAnalysis:
        """Margins, Ms and bandwidth of a loop (:func:`servotune.frequency.analyse_loop`).

        Parameters
        ----------
        loop : {"velocity", "position"}
        omega : array_like, optional
            Dense grid [rad/s].

        Returns
        -------
        LoopAnalysis
        """
        return frequency.analyse_loop(self._loop(loop), omega)

    def response(self, omega, force: str, outputs) -> np.ndarray:
        """Return outputs per a force input of the plant at ``omega``.

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s].
        force : str
            Input signal (``f_wp_x``).
        outputs : sequence of str
            Output signals.

        Returns
        -------
        numpy.ndarray
            Complex, shape ``(len(outputs), len(omega))``.
        """
        outputs = list(outputs)
        return frequency.fast_frequency_response(self.plant, omega, inputs=[force],
                                                 outputs=outputs).complex.reshape(
            len(outputs), -1)

    def compliance(self, omega, force: str = "wp.x", outputs=("wp.x",)) -> np.ndarray:
        """Return the work-piece compliance [m/N] (the loop must be stable).

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s].
        force : str
            DOF of the force.
        outputs : sequence of str
            DOFs of the displacements.

        Returns
        -------
        numpy.ndarray
            Complex, shape ``(len(outputs), len(omega))``.
        """
        return self.response(omega, signal_name(force, "f_"), [signal_name(o) for o in outputs])


def closed_loop(structure: ModalModel, drive: Drive | None, contact: Contact | None = None,
                pads=()) -> ContinuousAxis | SampledAxis:
    """Return the controlled axis: continuous, or the sampled-data system of a digital drive.

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    drive : Drive or None
        The drive; a digital one (:class:`~servotune.drive.Sampling` with periods) gives a
        :class:`~servotune.digital.SampledAxis`.
    contact : Contact, optional
        The guide-way contact (default: free).
    pads : sequence of str
        The pad DOFs where the contact acts.

    Returns
    -------
    ContinuousAxis or SampledAxis
        With ``is_stable``, ``require_stable``, ``loop_response``, ``analyse_loop``,
        ``compliance`` and ``response``.

    Examples
    --------
    >>> from servotune.structure import ModalModel
    >>> axis = closed_loop(ModalModel([[1.0]], [[1e4]], ["wp.x"], damping_ratio=0.02), None)
    >>> round(abs(complex(axis.compliance([1.0])[0, 0])) * 1e4, 4)   # static: 1/k
    1.0001
    """
    if drive is not None and not drive.digital.is_continuous:
        return SampledAxis(structure, drive, contact, pads)
    return ContinuousAxis(structure, drive, contact, pads)


def axis_compliance(structure: ModalModel, omega, drive: Drive | None,
                    contact: Contact | None = None, pads=(), force: str = "wp.x",
                    outputs=("wp.x",)) -> np.ndarray:
    """Return the compliance of the controlled axis, continuous or sampled.

    A continuous drive (or none) by the port coupling of
    :func:`servotune.frequency.port_compliance`; a digital drive as the fundamental of the
    sampled-data response (:meth:`servotune.digital.SampledAxis.compliance`). Stability is not
    checked (as :func:`~servotune.frequency.port_compliance` without ``check_stability``).

    Parameters
    ----------
    structure : ModalModel
        The reduced structure.
    omega : array_like
        Angular frequencies [rad/s], 1-D, > 0.
    drive : Drive or None
        The drive.
    contact : Contact, optional
        The guide-way contact (default: free).
    pads : sequence of str
        The pad DOFs where the contact acts.
    force : str
        DOF of the force.
    outputs : sequence of str
        DOFs of the displacements.

    Returns
    -------
    numpy.ndarray
        Complex [m/N], shape ``(len(outputs), len(omega))``.
    """
    if drive is not None and not drive.digital.is_continuous:
        return SampledAxis(structure, drive, contact, pads).compliance(omega, force, outputs)
    return frequency.port_compliance(structure, omega, drive, contact, pads, force=force,
                                     outputs=outputs)
