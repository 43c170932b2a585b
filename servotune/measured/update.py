"""Model updating: the axis' reduced model corrected so that its FRF matches a measured one.

The problem: a receptance H(w) measured at one DOF of the axis in a known test configuration
(the drive switched off, the guide-way pads stuck: the structure with the pads' presliding
contact and no motor torque) and the reduced model's prediction of it, G(w; p), differ. Find
the natural frequencies and modal damping ratios p of a few modes of the stored model (the
:class:`~servotune.structure.ModalModel` of ``[structure]``, pads and rotor free) that solve::

    minimise over p   sum_k |ln G(w_k; p) - ln H(w_k)|^2     over the lines w_k of the band
    subject to        (1 - b) omega_j <= omega_j' <= (1 + b) omega_j,
                      zeta_min <= zeta_j' <= zeta_max

(the complex logarithm: its real part the log-magnitude ratio, its imaginary part the phase
difference, so that every line counts alike, the anti-resonances as much as the peaks), b = 0.2,
zeta in [0.001, 0.2] by default (:class:`UpdateBounds`).

The stages, each a named function:

1. :func:`measured_configuration`: the model of the test set-up, the structure with the
   contact's springs and dampers shared at the pads, and :func:`configuration_modes`: its
   complex modes, each with its residue at the DOF and the sensitivity of its pole to every
   stored mode's frequency [3]_.
2. :func:`match_modes`: each identified mode to the configuration mode nearest in frequency
   among those that show at the DOF, and that mode to the stored mode whose frequency moves its
   pole most. With one measured DOF there is no mode shape to compare: the modal assurance
   criterion (MAC) needs several response points, so frequency and visibility at the DOF are
   all there is to match by.
3. :func:`update_model`: ``scipy.optimize.least_squares`` (trust-region reflective, within the
   bounds) from the identified modes, and the FRF error before and after.
4. :func:`write_updated_axis`: a copy of the axis folder with the updated matrices.

The correction of one mode's frequency keeps its shape: with Phi^T M Phi = I (so Phi^-1 =
Phi^T M), K = Phi^-T diag(omega^2) Phi^-1 = M Phi diag(omega^2) Phi^T M, and changing omega_j
to omega_j' for the chosen modes S gives

    K' = K + M Phi_S diag(omega_j'^2 - omega_j^2) Phi_S^T M,

whose eigenvectors are still Phi (Phi^T K' Phi = diag(omega'^2)), so K' stays positive
semi-definite, rigid-body modes stay at 0, and the damping ratios map onto the same modes:
D' = M Phi diag(2 zeta' omega') Phi^T M, as :class:`~servotune.structure.ModalModel` builds it
from ``modal_damping`` [1]_ [2]_.

References
----------
.. [1] M. I. Friswell, J. E. Mottershead, "Finite Element Model Updating in Structural
   Dynamics", Kluwer (1995), ch. 2 (modal decomposition of M and K), ch. 7 (penalty methods:
   sensitivities, bounds, least squares over FRF data).
.. [2] D. J. Ewins, "Modal Testing: Theory, Practice and Application", 2nd ed., Research
   Studies Press (2000), sec 2.3 (mass-normalised modes, K = M Phi diag(omega^2) Phi^T M).
.. [3] P. Lancaster, "On eigenvalues of matrices dependent on a parameter", Numerische
   Mathematik 6 (1964) 377-387 (derivatives of the eigenvalues of lambda-matrices: the
   sensitivity of a damped pole, used in :func:`configuration_modes`).
"""

from __future__ import annotations

import math
import re
import shutil
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.linalg

from ..structure.model import ModalModel
from ..units import HZ_PER_RAD_S
from .ema import IdentifiedMode

__all__ = [
    "UpdateBounds",
    "ConfigurationModes",
    "ModeMatch",
    "ModeUpdate",
    "ModelUpdate",
    "updated_structure",
    "measured_configuration",
    "configuration_modes",
    "predicted_frf",
    "StructureTest",
    "match_modes",
    "update_model",
    "write_updated_axis",
]

#: the power of j w that turns a receptance into each quantity
_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}

#: a configuration mode shows at the DOF when its own peak is at least this share of |G| there
VISIBLE = 0.2


@dataclass(frozen=True)
class UpdateBounds:
    """The bounds of the updated parameters.

    Attributes
    ----------
    frequency_ratio : float
        Each updated natural frequency stays within (1 +- frequency_ratio) of the model's
        (default 0.2); an identified mode farther than that from every model mode is left out.
    damping_range : tuple of float
        The damping ratios allowed (default (0.001, 0.2)).
    """

    frequency_ratio: float = 0.2
    damping_range: tuple[float, float] = (0.001, 0.2)

    def __post_init__(self):
        if not 0 < self.frequency_ratio < 1:
            raise ValueError(f"UpdateBounds.frequency_ratio must be in (0, 1), got "
                             f"{self.frequency_ratio!r}")
        low, high = (float(v) for v in self.damping_range)
        if not 0 < low < high < 1:
            raise ValueError("UpdateBounds.damping_range must be (low, high) with 0 < low < "
                             f"high < 1, got {self.damping_range!r}")
        object.__setattr__(self, "damping_range", (low, high))

    def describe(self) -> str:
        """Return the bounds in one phrase, for reports.

        Returns
        -------
        str
        """
        low, high = self.damping_range
        return (f"frequencies within +-{100 * self.frequency_ratio:g} % of the model's, damping "
                f"ratios in [{low:g}, {high:g}]")


def _stored_damping(structure: ModalModel) -> np.ndarray:
    """The modal damping ratio of every stored mode (the ratios given, per mode)."""
    if structure.damping_ratio is None:
        raise ValueError("the structure has a physical damping matrix, not modal damping "
                         "ratios: updating corrects modal damping (modal_damping in "
                         "[structure]); build the model with damping ratios")
    return np.broadcast_to(np.asarray(structure.damping_ratio, float), (structure.n,)).copy()


def updated_structure(structure: ModalModel, modes, omega, zeta) -> ModalModel:
    """Return the model with new natural frequencies and damping ratios on some of its modes.

    Parameters
    ----------
    structure : ModalModel
        The model, with modal damping ratios.
    modes : sequence of int
        The modes changed (0-based, in the order of
        :meth:`~servotune.structure.ModalModel.natural_frequencies`).
    omega : sequence of float
        Their new natural frequencies [rad/s], > 0.
    zeta : sequence of float
        Their new damping ratios [-], in [0, 1).

    Returns
    -------
    ModalModel
        The same M and DOFs, K' = K + M Phi_S diag(omega'^2 - omega^2) Phi_S^T M, and the damping
        ratios (the others as before) in the order of the new frequencies: the model
        ``[structure]`` gives with these matrices and that ``modal_damping`` list.

    Raises
    ------
    ValueError
        A structure with a physical damping matrix, a rigid-body mode among ``modes``, or
        values of different lengths.

    Notes
    -----
    With Phi^T M Phi = I, K = M Phi diag(omega^2) Phi^T M (see the module); the change keeps
    the mode shapes, so the new damping matrix M Phi diag(2 zeta' omega') Phi^T M is modal on
    the same modes (Friswell and Mottershead 1995, ch. 2).

    Examples
    --------
    A two-mass chain; the first mode raised from 50 to 60 rad/s keeps its shape:

    >>> import numpy as np
    >>> chain = ModalModel([[1.0, 0], [0, 1.0]], [[2e3, -1e3], [-1e3, 2e3]], ["a", "b"])
    >>> w = chain.natural_frequencies()
    >>> new = updated_structure(chain, [0], [1.2 * w[0]], [0.05])
    >>> bool(np.allclose(new.natural_frequencies(), [1.2 * w[0], w[1]]))
    True
    >>> bool(np.allclose(abs(new.mode_shapes()), abs(chain.mode_shapes())))
    True
    """
    modes = [int(j) for j in modes]
    omega = np.asarray(omega, float).reshape(-1)
    zeta_new = np.asarray(zeta, float).reshape(-1)
    if not len(modes) == omega.size == zeta_new.size:
        raise ValueError(f"{len(modes)} modes, {omega.size} frequencies and {zeta_new.size} "
                         "damping ratios: give one of each per mode")
    w0, phi = structure.natural_frequencies(), structure.mode_shapes()
    ratios = _stored_damping(structure)
    if any(w0[j] == 0 for j in modes):
        raise ValueError("a rigid-body mode (0 Hz) has no frequency to correct")
    if np.any(omega <= 0) or not np.all(np.isfinite(omega)):
        raise ValueError("the new natural frequencies must be finite and > 0")
    m = structure.mass
    mphi = m @ phi[:, modes]
    k = structure.stiffness + mphi @ np.diag(omega**2 - w0[modes] ** 2) @ mphi.T
    w_new = w0.copy()
    w_new[modes] = omega
    ratios[modes] = zeta_new
    order = np.argsort(w_new, kind="stable")
    return ModalModel(m, 0.5 * (k + k.T), structure.dofs, damping_ratio=ratios[order])


def measured_configuration(structure: ModalModel, contact, pads) -> ModalModel:
    """Return the structure in a test set-up: the contact at the pads, no drive.

    Parameters
    ----------
    structure : ModalModel
        The stored model (pads and rotor free).
    contact : servotune.plant.Contact
        The guide-way contact, axis totals shared equally by the pads: a spring and damper
        (``stiction``, ``viscous``, ``equivalent``), ``locked`` or ``free``.
    pads : sequence of str
        The pad DOFs.

    Returns
    -------
    ModalModel
        The structure with the contact's springs and dampers on the pads, or with the pads
        held (locked); no motor torque acts (the drive switched off: the rotor free).

    Raises
    ------
    ValueError
        A dynamic contact (``sliding``): the test configuration is a standstill.
    """
    pads = list(pads)
    if contact.pads == "free":
        return structure
    if contact.pads == "locked":
        return structure.locked(pads)
    if contact.system is not None:
        raise ValueError(f"a {contact.kind!r} contact is dynamic: a model updated from a "
                         "measurement at standstill takes a spring-and-damper contact such as "
                         "'stiction'")
    n = len(pads)
    return structure.with_added(stiffness={p: contact.stiffness / n for p in pads},
                                damping={p: contact.damping / n for p in pads})


@dataclass(frozen=True)
class ConfigurationModes:
    """The complex modes of a test configuration (stage 1).

    Attributes
    ----------
    poles : numpy.ndarray
        lambda_r [rad/s], positive imaginary part, by increasing |lambda|.
    residues : numpy.ndarray
        The receptance residue at the DOF, R_r = x_r(dof)^2 / a_r [m/(N s)].
    visible : numpy.ndarray
        |R_r / Re lambda_r| (the mode's own peak) over |G| of the whole model at Im lambda_r.
    sensitivity : numpy.ndarray
        |d ln lambda_r / d ln omega_j| for every stored mode j, shape (modes, stored modes): the
        share of each stored mode's frequency in each pole's (about 1 for a mode alone).
    """

    poles: np.ndarray
    residues: np.ndarray
    visible: np.ndarray
    sensitivity: np.ndarray

    @property
    def frequency(self) -> np.ndarray:
        """Natural frequencies |lambda| [rad/s]."""
        return np.abs(self.poles)

    @property
    def damping_ratio(self) -> np.ndarray:
        """Damping ratios -Re(lambda)/|lambda|."""
        return -self.poles.real / np.abs(self.poles)


def configuration_modes(structure: ModalModel, configuration: ModalModel,
                        dof: str) -> ConfigurationModes:
    """Return the complex modes of a test configuration, their residues and sensitivities.

    Parameters
    ----------
    structure : ModalModel
        The stored model (whose modes are the parameters).
    configuration : ModalModel
        The test configuration (:func:`measured_configuration`), on the same DOFs or some held.
    dof : str
        The measured DOF (force and response).

    Returns
    -------
    ConfigurationModes
        The underdamped modes.

    Notes
    -----
    For (lambda^2 M + lambda D + K) x = 0 with the symmetric matrices of the configuration and
    a_r = x_r^T (2 lambda_r M + D) x_r, the receptance is sum_r x_r x_r^T / (a_r (s - lambda_r))
    over all 2n poles, and a change dK of the stiffness moves a pole by
    d lambda_r = -x_r^T dK x_r / a_r (Lancaster 1964). For dK = M phi_j phi_j^T M d(omega_j^2)
    (the frequency of stored mode j, see the module):
    d ln lambda_r / d ln omega_j = -2 omega_j^2 (phi_j^T M x_r)^2 / (a_r lambda_r).
    """
    m, k, d = configuration.mass, configuration.stiffness, configuration.damping
    n = configuration.n
    a_mat = np.block([[np.zeros((n, n)), np.eye(n)],
                      [-np.linalg.solve(m, k), -np.linalg.solve(m, d)]])
    lam, vec = scipy.linalg.eig(a_mat)
    keep = np.flatnonzero(lam.imag > 1e-9 * np.abs(lam).max())
    keep = keep[np.argsort(np.abs(lam[keep]))]
    lam, x = lam[keep], vec[:n, keep]
    a = np.einsum("ir,ij,jr->r", x, m, x) * 2 * lam + np.einsum("ir,ij,jr->r", x, d, x)
    i = int(configuration.index(dof))
    residues = x[i] ** 2 / a
    # the stored modes on the configuration's DOFs (held DOFs dropped)
    rows = structure.index(list(configuration.dofs))
    phi = structure.mode_shapes()
    w = structure.natural_frequencies()
    proj = (phi[rows].T @ m) @ x  # phi_j^T M x_r on the configuration's DOFs
    sensitivity = np.abs(2 * w[:, None] ** 2 * proj**2 / (a * lam)[None, :]).T
    whole = configuration.port_receptance(lam.imag, [dof], [dof])[:, 0, 0]
    own = np.abs(residues / lam.real)
    visible = own / np.maximum(np.abs(whole), 1e-300)
    return ConfigurationModes(lam, residues, visible, sensitivity)


def predicted_frf(structure: ModalModel, omega, contact, pads, dof: str,
                  quantity: str = "receptance") -> np.ndarray:
    """Return the model's FRF of the test configuration at a DOF.

    Parameters
    ----------
    structure : ModalModel
        The structure.
    omega : array_like
        Angular frequencies [rad/s], > 0.
    contact : servotune.plant.Contact
        The guide-way contact.
    pads : sequence of str
        The pad DOFs.
    dof : str
        Force and response DOF.
    quantity : str
        ``"receptance"``, ``"mobility"`` or ``"accelerance"``.

    Returns
    -------
    numpy.ndarray
        Complex, SI, shape of ``omega``: (j w)^p times the receptance of
        :func:`servotune.frequency.port_compliance` without drive.
    """
    from ..frequency import port_compliance

    omega = np.asarray(omega, float)
    h = port_compliance(structure, omega, None, contact, list(pads), force=dof,
                        outputs=(dof,))[0]
    return (1j * omega) ** _POWER[quantity] * h


@dataclass(frozen=True)
class StructureTest:
    """The test configuration of a ``structure`` measurement: drive off, pads on a contact.

    The model side of an update: which FRF the model predicts for the measurement and which
    complex modes it has. :func:`update_model` asks a test configuration for ``frf``,
    ``modes``, ``check`` and ``describe``; the closed-loop one is
    :class:`servotune.measured.closed_loop.ClosedLoopTest`.

    Attributes
    ----------
    contact : servotune.plant.Contact
        The guide-way contact during the test (``stiction`` for pads stuck).
    pads : tuple of str
        The pad DOFs.
    quantity : str
        ``"receptance"``, ``"mobility"`` or ``"accelerance"``.
    """

    contact: object
    pads: tuple[str, ...]
    quantity: str = "receptance"

    kind = "structure"
    notes = ()

    def frf(self, structure: ModalModel, omega, dof: str) -> np.ndarray:
        """Return the model's FRF of the test at a DOF (:func:`predicted_frf`).

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
            Complex, SI, shape of ``omega``.
        """
        return predicted_frf(structure, omega, self.contact, self.pads, dof, self.quantity)

    def modes(self, structure: ModalModel, dof: str) -> ConfigurationModes:
        """Return the complex modes of the test configuration (:func:`configuration_modes`).

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
        return configuration_modes(structure, measured_configuration(structure, self.contact,
                                                                     self.pads), dof)

    def check(self, structure: ModalModel) -> None:
        """Check that the model can stand for the test (a structure with a contact always can).

        Parameters
        ----------
        structure : ModalModel
            The structure.
        """

    def describe(self) -> str:
        """Return the test configuration in one phrase, for reports.

        Returns
        -------
        str
        """
        return f"drive off (rotor free), pads: {self.contact.note}"


@dataclass(frozen=True)
class ModeMatch:
    """One identified mode joined to the model (stage 2).

    Attributes
    ----------
    identified : IdentifiedMode
        The identified mode.
    pole : complex
        The matched pole of the test configuration [rad/s].
    mode : int
        The stored mode updated for it (0-based).
    share : float
        |d ln lambda / d ln omega_mode|: how much of the pole's frequency that mode's is.
    """

    identified: IdentifiedMode
    pole: complex
    mode: int
    share: float


def match_modes(structure: ModalModel, modes: ConfigurationModes, identified,
                bounds: UpdateBounds = UpdateBounds()) -> tuple[list[ModeMatch], list[str]]:
    """Join identified modes to configuration modes and to the stored modes they update.

    Parameters
    ----------
    structure : ModalModel
        The stored model.
    modes : ConfigurationModes
        The test configuration's modes.
    identified : sequence of IdentifiedMode
        The identified modes.
    bounds : UpdateBounds
        A match farther in frequency than ``bounds.frequency_ratio`` is refused.

    Returns
    -------
    matches : list of ModeMatch
        By increasing frequency.
    notes : list of str
        The identified modes left out, and why.

    Notes
    -----
    The rule: an identified mode goes with the configuration mode nearest in frequency among
    those that show at the DOF (their own peak at least ``VISIBLE`` = 0.2 of the model's |G|
    there); that mode with the stored flexible mode of the largest sensitivity not taken yet.
    No MAC: one measured DOF has no shape to compare.
    """
    notes, matches, taken = [], [], set()
    w_stored = structure.natural_frequencies()
    show = np.flatnonzero(modes.visible >= VISIBLE)
    for mode in sorted(identified, key=lambda m: m.frequency):
        f_hz = mode.frequency * HZ_PER_RAD_S
        if not show.size:
            notes.append(f"{f_hz:.4g} Hz: no mode of the model shows at the DOF")
            continue
        r = int(show[np.argmin(np.abs(modes.frequency[show] - mode.frequency))])
        w_r = modes.frequency[r]
        if abs(mode.frequency - w_r) > bounds.frequency_ratio * w_r:
            notes.append(f"{f_hz:.4g} Hz was left out: the nearest mode of the model that shows "
                         f"at the DOF is at {w_r * HZ_PER_RAD_S:.4g} Hz, beyond the bounds")
            continue
        ranked = [j for j in np.argsort(modes.sensitivity[r])[::-1]
                  if w_stored[j] > 0 and int(j) not in taken]
        if not ranked:
            notes.append(f"{f_hz:.4g} Hz was left out: no stored mode left to update")
            continue
        j = int(ranked[0])
        share = float(modes.sensitivity[r, j])
        if any(m.pole == modes.poles[r] for m in matches):
            notes.append(f"{f_hz:.4g} Hz was left out: its model mode at "
                         f"{w_r * HZ_PER_RAD_S:.4g} Hz is matched to another identified mode")
            continue
        taken.add(j)
        matches.append(ModeMatch(mode, complex(modes.poles[r]), j, share))
    return matches, notes


@dataclass(frozen=True)
class ModeUpdate:
    """One updated stored mode.

    Attributes
    ----------
    mode : int
        The stored mode (0-based, ascending frequency of the original model).
    frequency_before, frequency_after : float
        Its natural frequency [rad/s].
    damping_before, damping_after : float
        Its damping ratio.
    match : ModeMatch
        The identified mode and the configuration pole it was matched with.
    pole_after : complex
        The configuration pole nearest to the identified one after the update [rad/s].
    at_bound : tuple of str
        ``"frequency"``, ``"damping"``: the parameters that ended on a bound.
    """

    mode: int
    frequency_before: float
    frequency_after: float
    damping_before: float
    damping_after: float
    match: ModeMatch
    pole_after: complex
    at_bound: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        """Return the change with edge units (Hz).

        Returns
        -------
        dict
            ``mode`` (1-based), ``before`` and ``after`` (``frequency_hz``,
            ``damping_ratio``), ``frequency_change``, ``share``, ``identified`` and the
            test configuration's ``model_before`` and ``model_after`` (``frequency_hz``,
            ``damping_ratio``), ``at_bound``.
        """
        def pole(p):
            return {"frequency_hz": abs(p) * HZ_PER_RAD_S, "damping_ratio": -p.real / abs(p)}

        m = self.match.identified
        return {"mode": self.mode + 1,
                "before": {"frequency_hz": self.frequency_before * HZ_PER_RAD_S,
                           "damping_ratio": self.damping_before},
                "after": {"frequency_hz": self.frequency_after * HZ_PER_RAD_S,
                          "damping_ratio": self.damping_after},
                "frequency_change": self.frequency_after / self.frequency_before - 1,
                "share": self.match.share,
                "identified": {"frequency_hz": m.frequency * HZ_PER_RAD_S,
                               "damping_ratio": m.damping_ratio},
                "model_before": pole(self.match.pole), "model_after": pole(self.pole_after),
                "at_bound": list(self.at_bound)}


@dataclass(frozen=True)
class ModelUpdate:
    """The updated model and how well it matches the measurement.

    Attributes
    ----------
    structure : ModalModel
        The updated stored model.
    original : ModalModel
        The model before.
    parameters : tuple of ModeUpdate
        The updated modes.
    dof : str
        The measured DOF.
    contact : servotune.plant.Contact
        The test configuration's contact.
    pads : tuple of str
        Its pads.
    quantity : str
        The measured quantity.
    omega : numpy.ndarray
        The band's lines [rad/s].
    measured, before, after : numpy.ndarray
        The measurement and the model's FRF before and after, SI.
    frf_error_before, frf_error_after : float
        sqrt(sum |G - H|^2 / sum |H|^2) over the band.
    bounds : UpdateBounds
        The bounds.
    evaluations : int
        FRF evaluations of the least-squares fit.
    message : str
        The optimiser's.
    notes, warnings : tuple of str
        Remarks; what makes the result doubtful.
    """

    structure: ModalModel
    original: ModalModel
    parameters: tuple[ModeUpdate, ...]
    dof: str
    contact: object
    pads: tuple[str, ...]
    quantity: str
    omega: np.ndarray
    measured: np.ndarray
    before: np.ndarray
    after: np.ndarray
    frf_error_before: float
    frf_error_after: float
    bounds: UpdateBounds
    evaluations: int
    message: str
    notes: tuple[str, ...] = field(default=())
    warnings: tuple[str, ...] = field(default=())
    test: object = None

    @property
    def configuration(self) -> str:
        """The test configuration in one phrase (the test's ``describe()``)."""
        test = self.test or StructureTest(self.contact, self.pads, self.quantity)
        return test.describe()

    @property
    def modal_damping(self) -> list[float]:
        """The updated damping ratio of every mode, ascending frequency (``modal_damping``)."""
        return [float(z) for z in self.structure.damping_ratio]

    def rule(self) -> str:
        """Return what was updated and how, in one sentence.

        Returns
        -------
        str
        """
        return (f"the natural frequency (stiffness in the modal basis, K' = K + M Phi_S "
                f"diag(w'^2 - w^2) Phi_S^T M, shapes kept) and the modal damping ratio of "
                f"{len(self.parameters)} stored mode(s), each the one whose frequency moves an "
                f"identified mode's pole most, fitted by least squares on the complex log of "
                f"the {self.quantity} at {self.dof} (log-magnitude and phase) over the band, "
                f"{self.bounds.describe()}; the test configuration: {self.configuration}; "
                "modes matched by frequency among those that show at the DOF (no MAC with one "
                "measured DOF)")

    def to_dict(self) -> dict:
        """Return the results with edge units in the names.

        Returns
        -------
        dict
            ``dof``, ``configuration``, ``frf_error_before``, ``frf_error_after``,
            ``parameters``, ``modal_damping``, ``bounds``, ``rule``, ``evaluations``,
            ``message``, ``notes``, ``warnings``.
        """
        low, high = self.bounds.damping_range
        return {"dof": self.dof,
                "configuration": self.configuration,
                "frf_error_before": self.frf_error_before,
                "frf_error_after": self.frf_error_after,
                "parameters": [p.to_dict() for p in self.parameters],
                "modal_damping": self.modal_damping,
                "bounds": {"frequency_ratio": self.bounds.frequency_ratio,
                           "damping_range": [low, high]},
                "rule": self.rule(), "evaluations": self.evaluations,
                "message": self.message, "notes": list(self.notes),
                "warnings": list(self.warnings)}

    def plot(self):
        """Return the figure of the measurement and the model before and after.

        Returns
        -------
        matplotlib.figure.Figure
            See :func:`servotune.measured.figures.plot_model_update`.
        """
        from .figures import plot_model_update

        return plot_model_update(self)


def _error(model: np.ndarray, measured: np.ndarray) -> float:
    size = float(np.sum(np.abs(measured) ** 2))
    return math.sqrt(float(np.sum(np.abs(model - measured) ** 2)) / size) if size > 0 else math.inf


def update_model(structure: ModalModel, identification, contact, pads, dof: str = "wp.x",
                 bounds: UpdateBounds = UpdateBounds(), test=None) -> ModelUpdate:
    """Update a reduced model's modes so that its FRF matches a measured one.

    Parameters
    ----------
    structure : ModalModel
        The stored model of the axis (modal damping ratios).
    identification : ModalIdentification
        The modes identified from the measurement; its first FRF, over its band, is the one
        fitted: the driving-point FRF at ``dof`` in the test configuration.
    contact : servotune.plant.Contact
        The pads' contact during the test (``stiction`` for pads stuck).
    pads : sequence of str
        The pad DOFs.
    dof : str
        The measured DOF (default ``"wp.x"``).
    bounds : UpdateBounds
        Bounds of the frequencies and damping ratios.
    test : StructureTest or servotune.measured.closed_loop.ClosedLoopTest, optional
        The test configuration, whose ``frf`` is the model FRF fitted and whose ``modes`` are
        matched to the identified ones (default ``StructureTest(contact, pads, quantity)``:
        drive off, the pads on ``contact``).

    Returns
    -------
    ModelUpdate
        The updated model, the parameters before and after, the FRF errors.

    Raises
    ------
    ValueError
        No identified mode matches a mode of the model; a dynamic contact; a model without
        modal damping ratios; a model the test cannot take (``test.check``: an unstable
        closed loop).
    UnknownDofError
        A DOF the model does not have.

    See Also
    --------
    servotune.measured.ema.identify_modes : the identification it starts from.

    Notes
    -----
    The problem and the rule are in :mod:`servotune.measured.update`; the start: each stored
    mode's frequency moved by the first-order ratio of the identified to the model pole,
    ln(omega_j0 / omega_j) = ln(|lambda_id| / |lambda_r|) / share, its damping ratio scaled
    by zeta_id / zeta_r, both within the bounds.
    """
    from scipy.optimize import least_squares

    structure.index(dof)
    pads = tuple(pads)
    quantity = identification.frfs[0].quantity
    test = StructureTest(contact, pads, quantity) if test is None else test
    test.check(structure)
    omega = np.asarray(identification.omega, float)
    measured = np.asarray(identification.measured[0], complex)
    lines = np.abs(measured) > 0  # the log needs them; a line of exactly 0 carries nothing
    modes = test.modes(structure, dof)
    matches, notes = match_modes(structure, modes, identification.modes, bounds)
    notes = [*test.notes, *notes]
    if not matches:
        raise ValueError("no identified mode matches a mode of the model that shows at "
                         f"{dof} within the bounds ({bounds.describe()}): "
                         + "; ".join(notes or ["no mode identified"]))
    chosen = [m.mode for m in matches]
    w0 = structure.natural_frequencies()[chosen]
    z0 = _stored_damping(structure)[chosen]
    low_z, high_z = bounds.damping_range
    span = math.log1p(bounds.frequency_ratio), math.log1p(-bounds.frequency_ratio)
    start_w, start_z = [], []
    for m in matches:
        ratio = math.log(m.identified.frequency / abs(m.pole)) / max(m.share, 0.2)
        start_w.append(min(max(ratio, span[1]), span[0]))
        zeta_r = -m.pole.real / abs(m.pole)
        start_z.append(z0[len(start_z)] * m.identified.damping_ratio / zeta_r)
    x0 = np.concatenate([start_w, np.log(np.clip(start_z, low_z * 1.0001, high_z * 0.9999))])
    lower = np.concatenate([np.full(len(chosen), span[1]), np.full(len(chosen), math.log(low_z))])
    upper = np.concatenate([np.full(len(chosen), span[0]),
                            np.full(len(chosen), math.log(high_z))])
    x0 = np.clip(x0, lower + 1e-9, upper - 1e-9)
    log_h = np.log(measured[lines])
    n = len(chosen)

    def model_of(x):
        return updated_structure(structure, chosen, w0 * np.exp(x[:n]), np.exp(x[n:]))

    def residuals(x):
        g = test.frf(model_of(x), omega[lines], dof)
        r = np.log(g) - log_h
        r.imag = np.angle(np.exp(1j * r.imag))
        return np.concatenate([r.real, r.imag])

    fit = least_squares(residuals, x0, bounds=(lower, upper), method="trf", x_scale=1.0,
                        xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200 * (2 * n + 1))
    updated = model_of(fit.x)
    before = test.frf(structure, omega, dof)
    after = test.frf(updated, omega, dof)
    after_modes = test.modes(updated, dof)
    warnings = []
    try:
        test.check(updated)
    except ValueError as exc:
        warnings.append(f"the updated model: {exc}")
    parameters = []
    for k, m in enumerate(matches):
        w_new, z_new = float(w0[k] * math.exp(fit.x[k])), float(math.exp(fit.x[n + k]))
        edge = []
        if min(fit.x[k] - lower[k], upper[k] - fit.x[k]) < 1e-6:
            edge.append("frequency")
        if min(fit.x[n + k] - lower[n + k], upper[n + k] - fit.x[n + k]) < 1e-6:
            edge.append("damping")
        if edge:
            warnings.append(f"mode {m.mode + 1}: the {' and '.join(edge)} ended on its bound "
                            f"({bounds.describe()}): the model may lack what the measurement "
                            "shows (another mode, the contact's stiffness)")
        seen = np.flatnonzero(after_modes.visible >= VISIBLE)
        seen = seen if seen.size else np.arange(after_modes.poles.size)
        r = int(seen[np.argmin(np.abs(after_modes.poles[seen] - m.identified.pole))])
        parameters.append(ModeUpdate(m.mode, float(w0[k]), w_new, float(z0[k]), z_new, m,
                                     complex(after_modes.poles[r]), tuple(edge)))
    error_before, error_after = _error(before, measured), _error(after, measured)
    if error_after > 0.2:
        warnings.append(f"the updated model differs from the measurement by "
                        f"{100 * error_after:.0f} % (relative RMS over the band): the model "
                        "may lack what the measurement shows; look at the figure")
    if structure.reduction is not None:
        notes.append("the updated axis holds the reduced matrices: the Craig-Bampton "
                     "coverage of the original (its fixed-interface modes) is not carried "
                     "over")
    if len(identification.frfs) > 1:
        notes.append(f"only the first FRF ({identification.frfs[0].name}) was fitted: the "
                     f"driving point at {dof}")
    return ModelUpdate(updated, structure, tuple(parameters), dof, contact, pads, quantity,
                       omega, measured, before, after, error_before, error_after, bounds,
                       int(fit.nfev), str(fit.message), tuple(notes), tuple(warnings), test)


_HEADER = re.compile(r"^\s*\[\s*([^\[\]]+?)\s*\]\s*(#.*)?$")
_NAME = re.compile(r"^(\s*name\s*=\s*)(\"(?:[^\"\\]|\\.)*\"|'[^']*')")


def _updated_toml(text: str, block: str, name: str) -> str:
    """``text`` with ``[structure]`` and its sub-tables replaced by ``block`` (at its place)
    and the ``name`` of ``[axis]`` set (a line added when it has none)."""
    axis = tomllib.loads(text).get("axis")
    out, table, placed = [], None, False
    named = axis is not None and "name" not in axis  # a line to add after the header
    for line in text.splitlines(keepends=True):
        stripped = line.lstrip()
        header = _HEADER.match(line)
        if stripped.startswith("[["):
            table = "[["
        elif header:
            table = header.group(1).replace('"', "").replace(" ", "")
            if table.split(".")[0] == "structure" and not placed:
                out.append(block)
                placed = True
        if table is not None and table.split(".")[0] == "structure":
            continue
        if table == "axis" and _NAME.match(line):
            line = _NAME.sub(lambda m: m.group(1) + _toml_value(name), line, count=1)
        out.append(line)
        if header and table == "axis" and named:
            out.append(f"name = {_toml_value(name)}\n")
            named = False
    if not placed:
        out.append("\n" + block)
    if axis is None:
        out.insert(0, f"[axis]\nname = {_toml_value(name)}\n\n")
    return "".join(out)


def write_updated_axis(axis, update: ModelUpdate, folder, source: str = "") -> Path:
    """Write a copy of an axis folder with the updated structure.

    Parameters
    ----------
    axis : servotune.axis.Axis
        The axis that was updated (its folder is copied, never changed).
    update : ModelUpdate
        The update.
    folder : path-like
        The new axis folder; it must not exist.
    source : str
        What the update was fitted to, for the comment in ``axis.toml``.

    Returns
    -------
    pathlib.Path
        The folder: every file of the axis folder, ``structure.npz`` with the updated M, K and
        DOF names, and ``axis.toml`` whose ``[structure]`` names it with the updated
        ``modal_damping`` list and whose ``[axis] name`` ends in ``_updated`` (the rest of
        the file as it was).

    Raises
    ------
    FileExistsError
        When ``folder`` exists.
    ValueError
        When the axis file's ``[structure]`` cannot be replaced cleanly (keys given elsewhere
        as dotted keys); nothing is written then.
    """
    from ..structure.io import write_npz

    folder = Path(folder)
    if folder.exists():
        raise FileExistsError(f"{folder} exists; the updated axis goes into a new folder")
    original = Path(axis.file).read_text()
    tables = tomllib.loads(original)
    structure = update.structure
    changed = ", ".join(f"mode {p.mode + 1} {p.frequency_before * HZ_PER_RAD_S:.4g} -> "
                        f"{p.frequency_after * HZ_PER_RAD_S:.4g} Hz" for p in update.parameters)
    damping = ",\n    ".join(", ".join(f"{z:.6g}" for z in update.modal_damping[i:i + 8])
                             for i in range(0, structure.n, 8))
    block = (f"[structure]\n# updated by servotune identify{' from ' + source if source else ''}"
             f": FRF error at {update.dof} {100 * update.frf_error_before:.2f} % -> "
             f"{100 * update.frf_error_after:.2f} %;\n# {changed}\n"
             'file = "structure.npz"            # M and the DOFs as before, K updated\n'
             f"modal_damping = [                 # one per mode, ascending frequency\n"
             f"    {damping},\n]\n\n")
    name = f"{tables.get('axis', {}).get('name', Path(axis.path).name)}_updated"
    text = _updated_toml(original, block, name)
    try:
        parsed = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{axis.file}: the updated [structure] cannot be written into a copy "
                         f"of it ({exc}); write [structure] as one table") from None
    expected = {key: value for key, value in tables.items() if key != "structure"}
    expected["axis"] = dict(expected.get("axis", {}), name=name)
    got = {key: value for key, value in parsed.items() if key != "structure"}
    if got != expected or set(parsed.get("structure", {})) != {"file", "modal_damping"}:
        raise ValueError(f"{axis.file}: the updated [structure] cannot be written into a copy "
                         "of it cleanly; write [structure] as one table (no dotted "
                         "structure.* keys elsewhere)")
    target = folder.resolve()

    def ignore(directory, names):
        skip = {name for name in names if name == "__pycache__"}
        for name in names:
            path = (Path(directory) / name).resolve()
            if path == target or path in target.parents:
                skip.add(name)  # a results folder inside the axis folder
        return skip

    shutil.copytree(Path(axis.path), folder, ignore=ignore)
    write_npz(folder / "structure.npz", structure.mass, structure.stiffness, structure.dofs,
              force=True)
    (folder / "axis.toml").write_text(text)
    return folder


def _toml_value(value) -> str:
    """A TOML literal of a plain value of an ``[axis]`` table."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise ValueError(f"[axis] holds a value TOML cannot be written back plainly: {value!r}")
