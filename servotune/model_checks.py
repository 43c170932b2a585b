"""Checks of an axis model before it is tuned: does the structure fit the drive and the band?

Two checks on the structure (a :class:`~servotune.structure.ModalModel`) with the drive or the
requirements, each returning a frozen result with a verdict and a message that names what is
wrong and the fix:

* :func:`transmission_check`: the structure's own transmission, the static motion of the
  linear-encoder DOF per radian of the motor rotor (relative to the stator) with the guide-way
  pads free, against the drive's transmission ratio r [m/rad], sign included. With a linear
  encoder the position loop measures x_fb = u_encoder and commands the motor speed
  Kv (x_ref - x_fb) / r; if the structure moves the encoder by -r per radian (a flipped DOF
  direction in an FE export) the loop is positive feedback, whatever the gains. The check names
  which direction is flipped: the encoder's, when the other slide DOFs (pads, work piece) move
  with the motor as the drive says, or the rotor's, when they all move the other way.
* :func:`band_coverage`: whether the kept fixed-interface modes of a reduced structure cover
  the requirements' band with a margin (see :func:`servotune.structure.mode_coverage`).

:func:`axis_model_checks` runs both on an :class:`~servotune.axis.Axis`, as ``servotune tune``
and ``servotune bode`` do when they load it: a transmission that fails (a flipped direction, a
ratio off by more than the tolerance, an encoder the motor does not move) is an error
(:class:`ModelCheckError`, raised by :meth:`AxisModelChecks.require` before any tuning), a band
the kept modes do not cover a warning. Both are static: one solve with the stiffness and the
kept modes' frequencies.

The static motion: the rotor is turned by 1 rad with the stator held (or grounded), no other
load, and K_ff u_f = -K_fr solved for the remaining DOFs f (by Cholesky; a least-squares
solution if the structure can still move; the encoder's motion is then checked to be
determined).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from .drive import Drive
from .requirements import Requirements
from .structure.coverage import DEFAULT_MARGIN, BandCoverage, mode_coverage
from .structure.model import ModalModel
from .structure.ports import signed_direction

if TYPE_CHECKING:
    from .axis import Axis

__all__ = [
    "TRANSMISSION_TOLERANCE",
    "AxisModelChecks",
    "BandCoverage",
    "ModelCheckError",
    "TransmissionCheck",
    "axis_model_checks",
    "band_coverage",
    "transmission_check",
]

#: Largest accepted |structure ratio / drive ratio - 1| (both describe the same gear).
TRANSMISSION_TOLERANCE = 0.02


@dataclass(frozen=True)
class TransmissionCheck:
    """The structure's rotor-to-encoder motion against the drive's transmission ratio.

    Attributes
    ----------
    rotor, stator : str, str or None
        The motor DOFs (rad); ``stator`` None when grounded.
    encoder : str or None
        The linear-encoder DOF [m] (None when the drive has motor feedback and the structure
        has no such DOF).
    feedback : str
        "linear" or "motor".
    drive_ratio : float
        r [m/rad] of the drive (> 0).
    structure_ratio : float or None
        Encoder displacement per radian of rotor-minus-stator rotation from the structure
        [m/rad] (None when it could not be determined).
    slide_ratios : tuple of (str, float)
        The same for the other translational DOFs in the encoder's direction (pads, work
        piece), which tell a flipped encoder from a flipped rotor.
    status : str
        "ok", "flipped", "mismatch" (same sign, different size), "undetermined" or
        "not applicable" (motor feedback: the loop measures r times the motor angle).
    flipped : str or None
        The DOF whose direction is flipped, when it can be told.
    passed : bool
    message : str
    """

    rotor: str
    stator: str | None
    encoder: str | None
    feedback: str
    drive_ratio: float
    structure_ratio: float | None
    slide_ratios: tuple[tuple[str, float], ...]
    status: str
    flipped: str | None
    passed: bool
    message: str

    def to_dict(self) -> dict:
        """Plain values for JSON (SI).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"rotor": self.rotor, "stator": self.stator, "encoder": self.encoder,
                "feedback": self.feedback, "drive_ratio": self.drive_ratio,
                "structure_ratio": self.structure_ratio,
                "slide_ratios": {k: v for k, v in self.slide_ratios},
                "status": self.status, "flipped": self.flipped, "passed": self.passed,
                "message": self.message}


def _static_motion(structure: ModalModel, rotor: str, stator: str | None):
    """Displacements of all DOFs for 1 rad of rotor rotation (stator held), and a mask of the
    DOFs whose motion is determined (not free to move with the motor held)."""
    k = structure.stiffness
    r = int(structure.index(rotor))
    held = [r] + ([] if stator is None else [int(structure.index(stator))])
    free = np.array([i for i in range(structure.n) if i not in held], dtype=int)
    u = np.zeros(structure.n)
    u[r] = 1.0
    determined = np.ones(structure.n, dtype=bool)
    if free.size:
        k_ff = k[np.ix_(free, free)]
        rhs = -k[free, r]
        try:  # the usual case: the held motor holds the structure (one Cholesky solve)
            factor = scipy.linalg.cho_factor(k_ff)
            pivots = np.abs(np.diag(factor[0])) ** 2
            if pivots.min() > 1e-10 * max(float(np.abs(np.diag(k_ff)).max()), 1e-300):
                u[free] = scipy.linalg.cho_solve(factor, rhs)
                return u, determined
        except np.linalg.LinAlgError:
            pass
        w, v = np.linalg.eigh(k_ff)
        scale = max(float(np.abs(w).max(initial=0.0)), 1e-300)
        flexible = w > 1e-10 * scale
        # minimum-norm solution; components along the remaining rigid motions are undetermined
        u[free] = v[:, flexible] @ ((v[:, flexible].T @ rhs) / w[flexible])
        null = v[:, ~flexible]
        if null.size:
            determined[free] = np.abs(null).max(axis=1) < 1e-6
    return u, determined


def transmission_check(structure: ModalModel, drive: Drive,
                       tolerance: float = TRANSMISSION_TOLERANCE) -> TransmissionCheck:
    """Compare the structure's static rotor-to-encoder motion with the drive's ratio.

    Parameters
    ----------
    structure : ModalModel
        The axis structure with the guide-way pads free (``Axis.structure``).
    drive : Drive
        Its ``ratio`` [m/rad], ``motor.rotor``/``motor.stator``, ``encoder`` and ``feedback``.
    tolerance : float
        Largest accepted |structure ratio / drive ratio - 1|.

    Returns
    -------
    TransmissionCheck
        The structure's ratio, the drive's and whether they agree within ``tolerance``.

    Raises
    ------
    UnknownDofError
        The structure lacks the rotor, the stator or (linear feedback) the encoder DOF.

    Examples
    --------
    A slide (encoder on it) geared to a rotor by a spring on u - r theta, r = 2 mm/rad: the
    encoder moves +2 mm per radian, as the drive says.

    >>> from servotune.drive import Motor, PIController
    >>> r, k = 2e-3, 1e8
    >>> s = ModalModel([[500.0, 0], [0, 0.01]], [[k, -k * r], [-k * r, k * r * r]],
    ...                ["encoder.x", "motor.rotor"])
    >>> d = Drive(Motor(1.0, 1.0, 1.0, 1e-3, stator=None), ratio=r,
    ...           current_loop=PIController(1.0), velocity_loop=PIController(1.0), kv=10.0)
    >>> transmission_check(s, d).status
    'ok'
    """
    rotor, stator = drive.motor.rotor, drive.motor.stator
    encoder = drive.encoder
    structure.index([rotor] + ([] if stator is None else [stator]))
    if drive.feedback == "linear":
        structure.index(encoder)
    elif encoder not in structure.dofs:
        encoder = None
    u, determined = _static_motion(structure, rotor, stator)
    ratio = drive.ratio
    suffix = "." + encoder.rpartition(".")[2] if encoder else ".x"
    slides = tuple((d, float(u[i])) for i, d in enumerate(structure.dofs)
                   if d.endswith(suffix) and d != encoder and not d.startswith("mode.")
                   and determined[i] and abs(u[i]) > 0.1 * ratio)
    structure_ratio = None
    if encoder is not None and determined[int(structure.index(encoder))]:
        structure_ratio = float(u[int(structure.index(encoder))])
    common = dict(rotor=rotor, stator=stator, encoder=encoder, feedback=drive.feedback,
                  drive_ratio=ratio, structure_ratio=structure_ratio, slide_ratios=slides)
    per = f"per radian of {rotor}" + (f" relative to {stator}" if stator else "")
    if drive.feedback == "motor":
        shown = "" if structure_ratio is None else \
            f" (the structure moves {encoder} by {structure_ratio:.4g} m {per})"
        return TransmissionCheck(**common, status="not applicable", flipped=None, passed=True,
                                 message="position feedback from the motor encoder "
                                         f"(x_fb = r x motor angle): no sign to check{shown}")
    if structure_ratio is None or abs(structure_ratio) < 1e-6 * ratio:
        why = ("its motion is not determined with the motor held (the slide can move without "
               "turning the motor)" if structure_ratio is None else "it does not move")
        return TransmissionCheck(
            **common, status="undetermined", flipped=None, passed=False,
            message=f"turning {rotor} does not move the encoder {encoder}: {why}. Check that "
                    "the structure couples the motor to the slide (ball screw, belt) and that "
                    "the encoder DOF is on the slide")
    relative = structure_ratio / ratio - 1.0
    if structure_ratio < 0:
        others = [v for _, v in slides]
        moves = ", ".join(f"{d} {v:+.4g}" for d, v in slides)
        if others and sum(v > 0 for v in others) > len(others) / 2:
            flipped = encoder
            which = (f"the direction of the encoder DOF {encoder} is flipped: most of the "
                     f"slide moves positively, as the drive's sign says ({moves} m/rad)")
        elif others:
            flipped = rotor
            which = (f"the direction of the motor rotation {rotor} is flipped against the "
                     f"slide: most of it moves negatively too ({moves} m/rad)")
        else:
            flipped = None
            which = f"the direction of {encoder} or of {rotor} is flipped"
        example = "-ROTX" if flipped == rotor else "-UX"
        return TransmissionCheck(
            **common, status="flipped", flipped=flipped, passed=False,
            message=f"the structure moves the encoder {encoder} by {structure_ratio:.4g} m "
                    f"{per}, but the drive's ratio is +{ratio:.4g} m/rad: {which}. With linear "
                    "feedback the position loop would be positive feedback (unstable at any "
                    f"gain). Fix: reverse {flipped or 'that DOF'}, not the gains: give its "
                    "port's direction a minus sign in axis.toml, [structure.ports] "
                    f'"{flipped or "<port>"}" = {{ node = <node>, direction = "{example}" }} '
                    "(-x, -UX, -ROTX or Nastran's -1 ... as the export spells the direction; "
                    "the same in a ports CSV), or reverse the DOF in the export")
    if abs(relative) > tolerance:
        return TransmissionCheck(
            **common, status="mismatch", flipped=None, passed=False,
            message=f"the structure moves the encoder {encoder} by {structure_ratio:.4g} m "
                    f"{per}, the drive's ratio is {ratio:.4g} m/rad ({100 * relative:+.1f} %): "
                    "the loop gains would be off by that factor. Fix [drive.transmission] ratio "
                    "(slide travel per motor radian: lead / (2 pi) / belt ratio) or the "
                    "structure's transmission")
    return TransmissionCheck(
        **common, status="ok", flipped=None, passed=True,
        message=f"the structure moves the encoder {encoder} by {structure_ratio:.4g} m {per}; "
                f"the drive's ratio is {ratio:.4g} m/rad ({100 * relative:+.2f} %)")


def band_coverage(structure: ModalModel, requirements: Requirements | tuple | None = None,
                  margin: float = DEFAULT_MARGIN) -> BandCoverage:
    """Whether the kept fixed-interface modes of a reduced structure cover the band.

    Parameters
    ----------
    structure : ModalModel
        The axis structure (a Craig-Bampton model carries what its modes cover; a model read
        from a file is judged by its ``mode.*`` DOFs; an unreduced model is covered).
    requirements : Requirements or (float, float), optional
        The band of the compliance objective, ``Requirements.band`` [rad/s] (default: the
        default requirements, 5-300 Hz), or the band itself [rad/s].
    margin : float
        Every fixed-interface mode up to margin x the top of the band must be kept.

    Returns
    -------
    BandCoverage
        ``covered``, and a ``message`` naming the band, the frequency reached and the fix.
    """
    if requirements is None:
        requirements = Requirements()
    band = requirements.band if isinstance(requirements, Requirements) else requirements
    if len(tuple(band)) != 2 or not all(math.isfinite(float(x)) for x in band):
        raise ValueError(f"band must be (low, high) in rad/s, got {band!r}")
    return mode_coverage(structure, band, margin)


class ModelCheckError(ValueError):
    """An axis whose structure contradicts its drive (a flipped DOF direction, a transmission
    ratio that disagrees with the structure): tuning or analysing it would give wrong advice.
    The message names the DOF and the fix."""


@dataclass(frozen=True)
class AxisModelChecks:
    """The model checks of an axis: its transmission and the band coverage of its structure.

    Attributes
    ----------
    transmission : TransmissionCheck or None
        None for an axis without a drive.
    coverage : BandCoverage
        The kept fixed-interface modes against ``[requirements] band_hz``.
    source : str
        The axis file, for messages.
    """

    transmission: TransmissionCheck | None
    coverage: BandCoverage
    source: str = ""
    ports: tuple[tuple[str, str], ...] = ()
    """(DOF name, where the export has it) of the ports of ``[structure.ports]``."""
    grounded: str = ""
    """Why the slide cannot travel along its pads (the structure holds them to the ground,
    e.g. by the FE model's guide-way springs), with where and the fix; "" when it can."""
    port_fixes: tuple[tuple[str, str], ...] = ()
    """(DOF name, its line of ``[structure.ports]`` with the direction reversed) of the ports
    of ``[structure.ports]``: the fix of a flipped DOF, as axis.toml writes it."""

    @property
    def errors(self) -> tuple[str, ...]:
        """One line per failed check that makes the axis unusable (a grounded slide, the
        transmission; the transmission is not judged on a grounded slide)."""
        if self.grounded:
            return (f"model check (a slide held to the ground; [structure] against [friction] "
                    f"pads): {self.grounded}",)
        t = self.transmission
        if t is None or t.passed:
            return ()
        what = {"flipped": "a flipped direction", "mismatch": "the transmission ratio",
                "undetermined": "the encoder does not follow the motor"}.get(t.status, t.status)
        where = dict(self.ports).get(t.flipped) if t.flipped else None
        port = f" ({t.flipped} is {where} of the export)" if where else ""
        fix = dict(self.port_fixes).get(t.flipped) if t.flipped else None
        port += f"; in axis.toml write {fix}" if fix else ""
        return (f"model check ({what}; [structure] against [drive]): {t.message}{port}",)

    @property
    def warnings(self) -> tuple[str, ...]:
        """One line per check that makes results less reliable (the band coverage)."""
        return () if self.coverage.covered else (f"band coverage: {self.coverage.message}",)

    def require(self) -> AxisModelChecks:
        """Return these checks, or raise ModelCheckError when one of them is an error.

        Returns
        -------
        AxisModelChecks
            These checks (self), when none is an error.

        Raises
        ------
        ModelCheckError
            The transmission check failed; the message names the DOF and the fix.
        """
        if self.errors:
            where = f"{self.source}: " if self.source else ""
            raise ModelCheckError(where + "; ".join(self.errors))
        return self

    def to_dict(self) -> dict:
        """Plain values for JSON (SI).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"transmission": None if self.transmission is None
                else self.transmission.to_dict(),
                "band_coverage": self.coverage.to_dict(), "grounded": self.grounded or None,
                "errors": list(self.errors), "warnings": list(self.warnings)}


def axis_model_checks(axis: Axis, tolerance: float = TRANSMISSION_TOLERANCE,
                      margin: float = DEFAULT_MARGIN) -> AxisModelChecks:
    """The model checks of an axis: :func:`transmission_check` of its structure against its
    drive (when it has one) and :func:`band_coverage` of its structure against its
    requirements' band.

    Parameters
    ----------
    axis : Axis
        The axis: its structure, drive, pads and requirement band.
    tolerance : float
        Largest accepted |structure ratio / drive ratio - 1|.
    margin : float
        The kept fixed-interface modes must reach margin x the top of the band.

    Returns
    -------
    AxisModelChecks
        Call :meth:`~AxisModelChecks.require` to refuse an axis whose checks fail.

    Examples
    --------
    A slide (encoder on it) geared to a rotor, r = 2 mm/rad, as the drive says; then with the
    encoder's direction reversed, as a sign error in an export does: the encoder moves -r per
    radian, an error (its message names the fix: reverse the DOF, not the gains).

    >>> from pathlib import Path
    >>> from servotune.axis import Axis
    >>> from servotune.drive import Motor, PIController
    >>> r, k = 2e-3, 1e8
    >>> d = Drive(Motor(1.0, 1.0, 1.0, 1e-3, stator=None), ratio=r,
    ...           current_loop=PIController(1.0), velocity_loop=PIController(1.0), kv=10.0)
    >>> def slide(sign):
    ...     s = ModalModel([[500.0, 0], [0, 0.01]],
    ...                    [[k, -sign * k * r], [-sign * k * r, k * r * r]],
    ...                    ["encoder.x", "motor.rotor"])
    ...     return Axis("slide", "", Path("."), s, drive=d)
    >>> axis_model_checks(slide(+1)).errors
    ()
    >>> checks = axis_model_checks(slide(-1))
    >>> checks.transmission.status, round(checks.transmission.structure_ratio, 9)
    ('flipped', -0.002)
    >>> "reverse" in checks.errors[0] and "not the gains" in checks.errors[0]
    True
    """
    transmission, grounded = None, ""
    if axis.drive is not None and axis.friction is not None:
        from .thrust import moving_mass

        try:
            moving_mass(axis.structure, axis.pads)
        except ValueError as exc:
            if "no rigid-body travel" in str(exc):
                grounded = str(exc)
    if axis.drive is not None and not grounded:
        transmission = transmission_check(axis.structure, axis.drive, tolerance)
    coverage = band_coverage(axis.structure, axis.requirements, margin)
    return AxisModelChecks(transmission, coverage, str(axis.file), _port_places(axis),
                           grounded, _port_fixes(axis))


def _port_places(axis) -> tuple[tuple[str, str], ...]:
    """Where the export has each port of ``[structure.ports]`` (node and direction, or the
    position), for messages."""
    ports = axis.tables.get("structure", {}).get("ports")
    if not hasattr(ports, "items"):
        return ()
    out = []
    for name, spec in ports.items():
        if not hasattr(spec, "get"):
            continue
        direction = spec.get("direction")
        signed = signed_direction(direction)
        if signed is not None:
            direction = ("-" if signed[0] < 0 else "") + signed[1]
        if spec.get("node") is not None:
            place = f"node {spec['node']}, direction {direction},"
        else:
            place = (f"direction {direction} at the node nearest "
                     f"{list(spec.get('position') or ())} m")
        out.append((str(name), place))
    return tuple(out)


def _port_fixes(axis) -> tuple[tuple[str, str], ...]:
    """Each port of ``[structure.ports]`` with its direction reversed, as a line of axis.toml
    (``"encoder.x" = { node = 120, direction = "-UX" }``), for the fix of a flipped DOF."""
    ports = axis.tables.get("structure", {}).get("ports")
    if not hasattr(ports, "items"):
        return ()
    out = []
    for name, spec in ports.items():
        if not hasattr(spec, "get") or signed_direction(spec.get("direction")) is None:
            continue
        text = str(spec["direction"]).strip()
        reversed_ = text[1:] if text[0] == "-" else "-" + text.removeprefix("+")
        if spec.get("node") is not None:
            where = f"node = {json.dumps(spec['node'])}"
        elif spec.get("position") is not None:
            where = f"position = {json.dumps(list(spec['position']))}"
        else:
            continue
        out.append((str(name), f'"{name}" = {{ {where}, direction = "{reversed_}" }}'))
    return tuple(out)
