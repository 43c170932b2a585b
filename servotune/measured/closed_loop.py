"""The closed-loop test configuration: the work-piece compliance under position control.

A ``closed-loop`` measurement is the compliance x/F at a DOF of the work piece (``wp.x`` by
default) with the axis under position control by its own drive and the guide ways standing,
the pads on the presliding contact of the axis' friction law (``stiction``): the quantity
``servotune compliance AXIS --contact stiction`` computes. :class:`ClosedLoopTest` is that
configuration for :func:`servotune.measured.update.update_model`: the model FRF it fits is the
closed-loop compliance of :func:`servotune.closed_loop.closed_loop` (the sampled-data one for
a digital drive, as ``servotune compliance`` takes it), so model and measurement are the same
quantity, and the parameters are the same as for a ``structure`` measurement: the natural
frequencies and damping ratios of the stored modes that move the identified poles most.

The poles of the closed loop are not the structure's modes: the drive holds the motor and the
slide, moves some poles and adds its own. The modes matched to the identified ones are those
of the closed loop itself, x' = A x + B f, y = C x (the drive in continuous time: a digital
drive's sampling and delays move the poles of the structure little below its Nyquist
frequency and have no finite state model here), each with

* its receptance residue at the DOF, R_r = (C v_r)(w_r^H B) / (w_r^H v_r), v_r and w_r the
  right and left eigenvectors of A;
* its sensitivity to each stored mode's frequency, |d ln lambda_r / d ln omega_j| =
  |w_r^H (dA/d ln omega_j) v_r / (w_r^H v_r lambda_r)| (first-order eigenvalue perturbation
  [1]_), dA by a forward difference of the plant built with omega_j raised by 1e-4 at the
  same damping ratio (:func:`servotune.measured.update.updated_structure`: the states are the
  physical DOFs and the drive's, so A changes only where K and D do).

References
----------
.. [1] J. H. Wilkinson, "The Algebraic Eigenvalue Problem", Clarendon Press (1965), ch. 2,
   sec 5-10 (first-order perturbation of a simple eigenvalue: w^H dA v / w^H v).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..closed_loop import closed_loop
from ..structure.model import ModalModel, signal_name
from .update import _POWER, ConfigurationModes, _stored_damping, updated_structure

__all__ = ["CLOSED_LOOP_CONTACT", "ClosedLoopTest", "closed_loop_modes"]

#: the guide ways stand during the measurement: the pads on the presliding contact
CLOSED_LOOP_CONTACT = "stiction"

#: the relative step of a stored mode's frequency for the pole sensitivities
_STEP = 1e-4


def _continuous(drive):
    """The drive with continuous sampling (no sampling, no delays)."""
    from ..drive import Sampling

    if drive.digital.is_continuous:
        return drive
    return dataclasses.replace(drive, sampling=Sampling.continuous())


def closed_loop_modes(structure: ModalModel, drive, contact, pads, dof: str) -> ConfigurationModes:
    """Return the complex modes of the closed loop, their residues at a DOF and sensitivities.

    Parameters
    ----------
    structure : ModalModel
        The stored model (its modes are the parameters), with modal damping ratios.
    drive : servotune.drive.Drive
        The drive; a digital one is taken in continuous time here.
    contact : servotune.plant.Contact
        The guide-way contact.
    pads : sequence of str
        The pad DOFs.
    dof : str
        The DOF of the force and the displacement.

    Returns
    -------
    ConfigurationModes
        The underdamped poles of the closed loop (positive imaginary part, by increasing
        modulus), the compliance residue of each at ``dof``, its visibility there (its own
        peak |R_r / Re lambda_r| over |G(j Im lambda_r)|) and its sensitivity to every stored
        mode's frequency (zero for rigid-body modes).

    Notes
    -----
    See the module: R_r = (C v_r)(w_r^H B)/(w_r^H v_r) and
    d lambda_r = w_r^H dA v_r / (w_r^H v_r) (Wilkinson 1965, ch. 2).
    """
    from ..plant import build_plant

    drive = _continuous(drive)
    pads = tuple(pads)
    plant = build_plant(structure, drive, contact, pads)
    force, output = signal_name(dof, "f_"), signal_name(dof)
    if force not in plant.input_labels or output not in plant.output_labels:
        raise ValueError(f"the closed-loop plant has no force input and displacement output at "
                         f"{dof} (inputs {', '.join(plant.input_labels)})")
    a = np.asarray(plant.A, float)
    b = np.asarray(plant.B, float)[:, plant.input_labels.index(force)]
    c = np.asarray(plant.C, float)[plant.output_labels.index(output)]
    d = float(np.asarray(plant.D, float)[plant.output_labels.index(output),
                                         plant.input_labels.index(force)])
    lam, left, right = scipy.linalg.eig(a, left=True, right=True)
    keep = np.flatnonzero(lam.imag > 1e-9 * np.abs(lam).max())
    keep = keep[np.argsort(np.abs(lam[keep]))]
    lam, left, right = lam[keep], left[:, keep], right[:, keep]
    norm = np.einsum("ir,ir->r", left.conj(), right)
    residues = (c @ right) * (left.conj().T @ b) / norm
    eye = np.eye(a.shape[0])
    whole = np.array([c @ np.linalg.solve(1j * p.imag * eye - a, b) + d for p in lam])
    visible = np.abs(residues / lam.real) / np.maximum(np.abs(whole), 1e-300)
    w = structure.natural_frequencies()
    zeta = _stored_damping(structure)
    sensitivity = np.zeros((lam.size, structure.n))
    for j in np.flatnonzero(w > 0):
        moved = updated_structure(structure, [j], [w[j] * (1 + _STEP)], [zeta[j]])
        delta = np.asarray(build_plant(moved, drive, contact, pads).A, float) - a
        change = np.einsum("ir,ij,jr->r", left.conj(), delta, right) / norm
        sensitivity[:, j] = np.abs(change / (lam * math.log1p(_STEP)))
    return ConfigurationModes(lam, residues, visible, sensitivity)


@dataclass(frozen=True)
class ClosedLoopTest:
    """The test configuration of a ``closed-loop`` measurement (see the module).

    Attributes
    ----------
    drive : servotune.drive.Drive
        The axis' drive, digital or continuous, as the axis file gives it.
    contact : servotune.plant.Contact
        The guide-way contact (the axis' ``stiction`` contact: the guide ways standing).
    pads : tuple of str
        The pad DOFs.
    quantity : str
        ``"receptance"`` (the compliance), ``"mobility"`` or ``"accelerance"``.
    """

    drive: object
    contact: object
    pads: tuple[str, ...]
    quantity: str = "receptance"

    kind = "closed-loop"

    def __post_init__(self):
        if self.quantity not in _POWER:
            raise ValueError(f"a closed-loop measurement is a receptance, mobility or "
                             f"accelerance, not a {self.quantity}")
        object.__setattr__(self, "pads", tuple(self.pads))

    @property
    def sampled(self) -> bool:
        """Whether the drive is digital (its compliance the sampled-data one)."""
        return not self.drive.digital.is_continuous

    def frf(self, structure: ModalModel, omega, dof: str) -> np.ndarray:
        """Return the model's closed-loop FRF at a DOF, the loop's stability not checked.

        Parameters
        ----------
        structure : ModalModel
            The structure.
        omega : array_like
            Angular frequencies [rad/s], > 0.
        dof : str
            Force and response DOF.

        Returns
        -------
        numpy.ndarray
            Complex, SI, shape of ``omega``: (j w)^p times the compliance of
            :func:`servotune.closed_loop.closed_loop` (what ``servotune compliance`` computes;
            the fundamental of the sampled-data response for a digital drive).
        """
        omega = np.asarray(omega, float)
        loop = closed_loop(structure, self.drive, self.contact, self.pads)
        h = loop.compliance(omega, dof, (dof,))[0]
        return (1j * omega) ** _POWER[self.quantity] * h

    def modes(self, structure: ModalModel, dof: str) -> ConfigurationModes:
        """Return the closed loop's complex modes at a DOF (:func:`closed_loop_modes`).

        Parameters
        ----------
        structure : ModalModel
            The stored model.
        dof : str
            The measured DOF.

        Returns
        -------
        ConfigurationModes
        """
        return closed_loop_modes(structure, self.drive, self.contact, self.pads, dof)

    def check(self, structure: ModalModel) -> None:
        """Raise ValueError when the closed loop with this structure is unstable.

        Parameters
        ----------
        structure : ModalModel
            The structure.

        Raises
        ------
        ValueError
            An unstable loop: its compliance means nothing.
        """
        loop = closed_loop(structure, self.drive, self.contact, self.pads)
        if not loop.is_stable():
            raise ValueError(f"the closed loop with the {self.drive_name} drive is unstable: a "
                             "compliance of an unstable loop means nothing")

    @property
    def notes(self) -> tuple[str, ...]:
        """What the reader of the update should know of this configuration."""
        if not self.sampled:
            return ()
        return ("the closed-loop poles matched to the identified modes are those of the drive "
                "in continuous time (no sampling, no delays); the FRF fitted is the sampled-data "
                "compliance",)

    @property
    def drive_name(self) -> str:
        """``"sampled"`` or ``"continuous"``."""
        return "sampled" if self.sampled else "continuous"

    def describe(self) -> str:
        """Return the test configuration in one phrase, for reports.

        Returns
        -------
        str
        """
        return (f"position control by the axis' {self.drive_name} drive, pads: "
                f"{self.contact.note}")
