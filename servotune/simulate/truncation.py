"""The structure a time simulation needs: a Craig-Bampton model without the fixed-interface modes
far above everything the simulation excites.

A time step of the simulation costs in proportion to the number of modes of the linear part
(:mod:`servotune.simulate.integrator`), and an FE export reduced with every fixed-interface
mode kept carries modes up to the MHz that no force of a sweep, no friction and no loop of the
drive moves dynamically. Dropping such a mode's coordinate from a Craig-Bampton model is the
reduction with one mode fewer: the constraint modes keep its static flexibility exactly (the
residual-flexibility correction is built into the reduction, Craig and Bampton 1968), and what
is lost is its dynamic amplification, ``(f / f_k)^2`` of its share at a frequency f well below
its own f_k.

:func:`simulation_structure` keeps every mode below ``max(10 f_top, f_s)`` (f_top the top of the
band the simulation judges, f_s the fastest sampling rate of the drive, so that every mode a
controller could see folded into its band stays), then checks the result against the full
model: the receptances between the DOFs the simulation uses (forces, pads, motor, encoder)
from the band's bottom to ``max(2 f_top, f_s / 2)``, each pair's largest deviation relative to
the geometric mean of the largest magnitudes of its two driving points. Above
:data:`TRUNCATION_TOLERANCE` the cut-off is doubled until it holds or every mode is kept.

References
----------
R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses", AIAA Journal
6 (1968) 1313-1319.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..structure.model import ModalModel

__all__ = ["Truncation", "simulation_structure", "TRUNCATION_TOLERANCE"]

#: Largest deviation of a port receptance of the truncated model from the full one, relative
#: to the pair's largest magnitude over the checked band.
TRUNCATION_TOLERANCE = 0.01
#: Frequencies of the check (log-spaced).
CHECK_POINTS = 400


@dataclass(frozen=True)
class Truncation:
    """What :func:`simulation_structure` kept.

    Attributes
    ----------
    structure : ModalModel
        The model to simulate (the given one when nothing was dropped).
    kept, total : int
        Fixed-interface modes kept and present.
    cutoff_hz : float
        Modes above this were dropped [Hz] (inf: none).
    checked_hz : (float, float)
        Band of the receptance check [Hz].
    deviation : float
        Largest relative deviation of a port receptance in that band (0 when nothing was
        dropped).
    """

    structure: ModalModel
    kept: int
    total: int
    cutoff_hz: float
    checked_hz: tuple[float, float]
    deviation: float

    @property
    def truncated(self) -> bool:
        """Whether modes were dropped."""
        return self.kept < self.total

    def describe(self) -> str:
        """Return one line for a report: what was simulated.

        Returns
        -------
        str
            The modes kept, the cut-off and the receptance check, or "all N modes".
        """
        if not self.truncated:
            return f"all {self.total} fixed-interface modes" if self.total else "the full model"
        return (f"{self.kept} of {self.total} fixed-interface modes (those below "
                f"{self.cutoff_hz:.4g} Hz; the others' static flexibility kept by the constraint "
                f"modes; port receptances within {100 * self.deviation:.2g} % of the full model "
                f"over {self.checked_hz[0]:.3g}-{self.checked_hz[1]:.4g} Hz)")


def _mode_frequencies_hz(structure: ModalModel) -> dict[int, float]:
    """Row -> frequency [Hz] of each fixed-interface mode coordinate (``mode.*``)."""
    out = {}
    for i, d in enumerate(structure.dofs):
        if d.startswith("mode."):
            k, m = structure.stiffness[i, i], structure.mass[i, i]
            out[i] = math.sqrt(max(k, 0.0) / m) / (2 * math.pi)
    return out


def _restricted(structure: ModalModel, rows, modes: dict) -> ModalModel:
    """The model on a subset of its coordinates: mass, stiffness and damping restricted (the
    Galerkin projection onto the kept coordinates)."""
    rows = np.asarray(rows)
    sub = np.ix_(rows, rows)
    info = structure.reduction
    if info is not None:
        kept = sorted(modes[i] for i in rows if i in modes)
        dropped = [f for i, f in modes.items() if i not in set(rows.tolist())]
        info = dataclasses.replace(info, fixed_interface_hz=tuple(kept),
                                   next_hz=min(dropped, default=info.next_hz),
                                   complete_below_hz=min(min(dropped, default=math.inf),
                                                         info.complete_below_hz))
    return ModalModel(structure.mass[sub], structure.stiffness[sub],
                      [structure.dofs[i] for i in rows], damping=structure.damping[sub],
                      reduction=info)


def _deviation(full: ModalModel, part: ModalModel, ports, omega) -> float:
    h_full = full.port_receptance(omega, ports, ports)
    h_part = part.port_receptance(omega, ports, ports)
    # each pair against the geometric mean of its two driving points (the units of a cross
    # receptance; a pair that is zero but for rounding is not judged against itself)
    drive = np.abs(np.diagonal(h_full, axis1=1, axis2=2)).max(axis=0)
    scale = np.sqrt(np.outer(drive, drive))
    scale = np.where(scale > 0, scale, 1.0)
    return float((np.abs(h_part - h_full).max(axis=0) / scale).max())


_CACHE: dict = {}


def simulation_structure(structure: ModalModel, ports, f_top_hz: float,
                         sample_rate_hz: float = 0.0, f_bottom_hz: float = 1.0) -> Truncation:
    """Return the structure a simulation needs (see the module docstring).

    Parameters
    ----------
    structure : ModalModel
        The axis' structure; models without ``mode.*`` coordinates are returned as they are.
    ports : sequence of str
        The DOFs the simulation drives or reads (work piece, pads, motor, encoder).
    f_top_hz : float
        Top of the band the simulation judges [Hz].
    sample_rate_hz : float
        The drive's fastest sampling rate [Hz] (0: a continuous drive).
    f_bottom_hz : float
        Bottom of the receptance check [Hz].

    Returns
    -------
    Truncation

    Examples
    --------
    A slide with one low and one very high fixed-interface mode: the high one is dropped for a
    band up to 100 Hz, its static flexibility stays.

    >>> m = np.diag([10.0, 1.0, 1.0]); m[0, 1] = m[1, 0] = 0.5; m[0, 2] = m[2, 0] = 0.5
    >>> k = np.diag([1e6, (2 * np.pi * 50) ** 2, (2 * np.pi * 1e5) ** 2])
    >>> t = simulation_structure(ModalModel(m, k, ["wp.x", "mode.1", "mode.2"]), ["wp.x"], 100.0)
    >>> t.structure.dofs, t.kept, t.total
    (('wp.x', 'mode.1'), 1, 2)
    """
    key = (id(structure), tuple(ports), float(f_top_hz), float(sample_rate_hz),
           float(f_bottom_hz))
    hit = _CACHE.get(key)
    if hit is not None and hit[0] is structure:
        return hit[1]
    modes = _mode_frequencies_hz(structure)
    ports = [p for p in dict.fromkeys(ports) if p in structure.dofs]
    hi = max(2.0 * f_top_hz, 0.5 * sample_rate_hz)
    checked = (float(f_bottom_hz), float(hi))
    result = Truncation(structure, len(modes), len(modes), math.inf, checked, 0.0)
    if modes and ports:
        omega = 2 * math.pi * np.geomspace(f_bottom_hz, hi, CHECK_POINTS)
        cutoff = max(10.0 * f_top_hz, sample_rate_hz)
        while cutoff < max(modes.values()):
            drop = {i for i, f in modes.items() if f > cutoff}
            part = _restricted(structure, [i for i in range(structure.n) if i not in drop], modes)
            dev = _deviation(structure, part, ports, omega)
            if dev <= TRUNCATION_TOLERANCE:
                result = Truncation(part, len(modes) - len(drop), len(modes), cutoff, checked,
                                    dev)
                break
            cutoff *= 2.0
    if len(_CACHE) > 8:
        _CACHE.clear()
    _CACHE[key] = (structure, result)
    return result
