"""Do the fixed-interface modes of a reduced model cover the frequency band of interest?

A Craig-Bampton model is accurate up to about the frequency of the fixed-interface modes it
keeps: above, the interior motion is represented by the constraint modes alone, which makes
resonances too high and compliance peaks wrong (a "mode" in the band can be an artefact of the
constraint modes). A common rule of practice is to keep every fixed-interface mode up to 1.5-2
times the highest frequency of interest; servotune's default margin is 1.5, the lower end. The
reduction check (:func:`~servotune.structure.reduction_check`, the reduced model against the
full one) tells whether that was enough for a given model.

References
----------
R. R. Craig, A. J. Kurdila, Fundamentals of Structural Dynamics, 2nd ed., Wiley (2006), ch 18
(component-mode synthesis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..units import RAD_S_PER_HZ
from .model import ModalModel

__all__ = ["DEFAULT_MARGIN", "BandCoverage", "fixed_interface_frequencies", "mode_coverage"]

DEFAULT_MARGIN = 1.5


def _finite(x):
    return float(x) if x is not None and math.isfinite(x) else None


@dataclass(frozen=True)
class BandCoverage:
    """The verdict on the kept fixed-interface modes against a frequency band.

    Attributes
    ----------
    band_hz : (float, float)
        The band of interest [Hz].
    margin : float
        Required ratio of the covered frequency to the top of the band.
    required_hz : float
        margin times the top of the band [Hz].
    reached_hz : float
        Highest kept fixed-interface mode [Hz] (0 with none kept).
    complete_below_hz : float
        Every fixed-interface mode below this frequency is kept [Hz] (``inf`` when all are;
        the highest kept mode when nothing more is known).
    n_modes : int
        Kept fixed-interface modes.
    reduced : bool
        Whether the model is a reduced one at all (a model without fixed-interface modes and
        without reduction information is taken as complete).
    covered : bool
    message : str
        The verdict in words; when not covered it names the band, the frequency reached and
        the fix.
    """

    band_hz: tuple[float, float]
    margin: float
    required_hz: float
    reached_hz: float
    complete_below_hz: float
    n_modes: int
    reduced: bool
    covered: bool
    message: str

    def to_dict(self) -> dict:
        """Plain values for JSON (``None`` for an unbounded frequency).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"band_hz": list(self.band_hz), "margin": self.margin,
                "required_hz": self.required_hz, "reached_hz": self.reached_hz,
                "complete_below_hz": _finite(self.complete_below_hz),
                "all_modes_kept": self.complete_below_hz == math.inf,
                "n_modes": self.n_modes, "reduced": self.reduced, "covered": self.covered,
                "message": self.message}


def fixed_interface_frequencies(model: ModalModel) -> np.ndarray:
    """Return the frequencies [Hz] of the fixed-interface modes of a reduced model.

    From its reduction information when it has it, else from its modal DOFs ``mode.*``
    (eigenvalues of their block of K and M, which for a Craig-Bampton model are diag(omega^2)
    and I); empty when it has neither.

    Parameters
    ----------
    model : ModalModel
        A reduced model.

    Returns
    -------
    numpy.ndarray
        The frequencies [Hz], ascending.
    """
    if model.reduction is not None:
        return np.array(model.reduction.fixed_interface_hz)
    q = [i for i, d in enumerate(model.dofs) if d.startswith("mode.")]
    if not q:
        return np.zeros(0)
    sub = np.ix_(q, q)
    w2 = np.linalg.eigvals(np.linalg.solve(model.mass[sub], model.stiffness[sub])).real
    return np.sort(np.sqrt(np.clip(w2, 0.0, None))) / RAD_S_PER_HZ


def mode_coverage(model: ModalModel, band, margin: float = DEFAULT_MARGIN) -> BandCoverage:
    """Whether the kept fixed-interface modes of ``model`` cover ``band`` with ``margin``.

    Parameters
    ----------
    model : ModalModel
        A reduced model (from :func:`~servotune.structure.craig_bampton`, with its reduction
        information, or read from a file with modal DOFs ``mode.*``).
    band : (float, float)
        The band of interest [rad/s] (as ``Requirements.band``).
    margin : float
        Every fixed-interface mode up to ``margin`` times the top of the band must be kept.

    Returns
    -------
    BandCoverage
        Covered when every fixed-interface mode below margin x band top is in the model: from
        the reduction information (the first mode not kept, found by a dense solution or a
        Sturm count), else from the highest kept mode.

    Examples
    --------
    A model whose one fixed-interface mode is at 100 Hz does not cover 5-300 Hz:

    >>> m = ModalModel([[1.0, 0.0], [0.0, 1.0]], [[1e6, 0.0], [0.0, (2 * math.pi * 100) ** 2]],
    ...                ["wp.x", "mode.1"])
    >>> c = mode_coverage(m, (2 * math.pi * 5, 2 * math.pi * 300))
    >>> c.covered, round(c.reached_hz, 6), c.required_hz
    (False, 100.0, 450.0)
    """
    lo, hi = (float(x) for x in band)
    if not (0 <= lo < hi and math.isfinite(hi)):
        raise ValueError(f"band must be 0 <= low < high [rad/s], got {band!r}")
    margin = float(margin)
    if not (math.isfinite(margin) and margin >= 1.0):
        raise ValueError(f"margin must be a number >= 1, got {margin!r}")
    band_hz = (lo / RAD_S_PER_HZ, hi / RAD_S_PER_HZ)
    required = margin * band_hz[1]
    f = fixed_interface_frequencies(model)
    info = model.reduction
    reached = float(f[-1]) if f.size else 0.0
    reduced = info is not None or f.size > 0
    if info is not None and not math.isnan(info.complete_below_hz):
        complete = max(info.complete_below_hz, reached)
    else:
        complete = reached if reduced else math.inf
    covered = complete >= required
    band_text = f"{band_hz[0]:g}-{band_hz[1]:g} Hz"
    if not reduced:
        message = "not a reduced model: no fixed-interface modes were left out"
    elif covered:
        message = (f"the {f.size} fixed-interface modes kept cover the band {band_text} with "
                   f"margin {margin:g} (every mode up to "
                   + ("the last one" if complete == math.inf else f"{complete:.4g} Hz")
                   + f" kept; {required:.4g} Hz needed)")
    else:
        message = (f"the {f.size} fixed-interface modes kept reach {reached:.4g} Hz, but the "
                   f"band {band_text} with margin {margin:g} needs every fixed-interface mode "
                   f"up to {required:.4g} Hz: above {reached:.4g} Hz the reduced model's "
                   "resonances and compliance are not reliable. Fix: reduce with "
                   f"f_max_hz = {math.ceil(required)} (reduce = {{ boundary = [...], "
                   f"f_max_hz = {math.ceil(required)} }} in axis.toml, or --f-max-hz "
                   f"{math.ceil(required)}) instead of a fixed number of modes")
    return BandCoverage(band_hz=band_hz, margin=margin, required_hz=required,
                        reached_hz=reached, complete_below_hz=complete, n_modes=int(f.size),
                        reduced=bool(reduced), covered=bool(covered), message=message)
