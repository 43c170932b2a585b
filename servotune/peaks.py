"""Peaks and resonances of sampled responses over a band, and the band that holds the modes.

One rule for every result that reports a peak or a resonance (the compliance curves of
:mod:`servotune.analysis`, the harmonic balance of :mod:`servotune.harmonic.compliance`, the
commands ``compliance``, ``nlcompliance``, ``modes``, ``bode`` and ``lobes``):

* The largest value of a curve sampled over a band is a resonance only when it lies strictly
  inside the band. At the band's first or last frequency it is the value at the edge: the
  response still rises there, so whatever peak it has lies outside the band. Such a maximum
  is flagged (``"low"`` or ``"high"``, :func:`extreme_edge`) and reported as no resonance
  (:class:`BandPeak`: ``resonance`` and ``peak`` are None; the text says which edge and how to
  widen the band).
* A rigid-body mode that moves the point (0 Hz: a work piece no control and no contact
  stiffness hold) makes the response grow without bound towards 0 Hz; no band can hold it, and
  the text says so instead of asking for a wider band.
* The default band of an analysis comes from the axis: its requirement band widened, with a
  margin (:data:`BAND_MARGIN`), to hold the structure's modes that carry a significant share of
  the work piece's motion (:func:`mode_band`, :data:`SIGNIFICANT_SHARE`).

Examples
--------
A spring-mass resonates at sqrt(k/m) = 100 rad/s. Sampled up to 80 rad/s its largest value is
at the upper edge, not a resonance; over 50-150 rad/s the resonance is found:

>>> import numpy as np
>>> h = lambda w: 1.0 / (1e4 - w**2 + 2j * 0.03 * 100.0 * w)
>>> w = np.linspace(10.0, 80.0, 141)
>>> below = band_peak(w, h(w))
>>> below.edge, below.resonance
('high', None)
>>> w = np.linspace(50.0, 150.0, 201)
>>> round(band_peak(w, h(w)).resonance, 1)
99.9
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .units import HZ_PER_RAD_S

__all__ = [
    "BAND_MARGIN",
    "SIGNIFICANT_SHARE",
    "BandPeak",
    "ModeBand",
    "band_peak",
    "chosen_band",
    "extreme_edge",
    "mode_band",
    "parabola_peak",
    "rigid_body_moves",
    "structure_peak",
]

#: A default band holds each work-piece mode with this factor of room: up to 1.3 f above the
#: highest, down to f / 1.3 below the lowest (a resonance's half-power band at 3 % damping is
#: +-3 %; the factor leaves room for the shift a drive or a contact gives it).
BAND_MARGIN = 1.3

#: A mode moves the work piece significantly when it carries at least this share of the static
#: compliance there (:meth:`servotune.structure.model.ModalModel.participation`).
SIGNIFICANT_SHARE = 0.05

_EDGES = ("low", "high")


def _hz(omega: float) -> str:
    return f"{omega * HZ_PER_RAD_S:.4g}"


def extreme_edge(values, minimum: bool = False) -> str | None:
    """Return which edge of its band the largest (or smallest) sample of a curve lies at.

    Samples that are not finite are left out (a sampled-data loop's response beyond its
    Nyquist frequency is NaN): an extreme at the last finite sample before them is not at the
    band's edge, as a sampled response is mirrored about its Nyquist frequency.

    Parameters
    ----------
    values : array_like, shape (K,)
        The real samples in increasing frequency (magnitudes, or real parts).
    minimum : bool
        The smallest sample instead of the largest (e.g. the minimum of Re G of chatter).

    Returns
    -------
    str or None
        ``"low"`` when the extreme is the first sample, ``"high"`` when it is the last, None
        when it lies inside (a single sample counts as ``"low"``).

    Raises
    ------
    ValueError
        If no sample is finite.

    Examples
    --------
    >>> extreme_edge([1.0, 2.0, 3.0]), extreme_edge([1.0, 3.0, 2.0]), extreme_edge([3.0, 2.0])
    ('high', None, 'low')
    """
    v = np.asarray(values, dtype=float).reshape(-1)
    finite = np.isfinite(v)
    if not finite.any():
        raise ValueError("no finite sample: no extreme to place in the band")
    w = np.where(finite, -v if minimum else v, -np.inf)
    i = int(np.argmax(w))
    if i == 0:
        return "low"
    if i == v.size - 1:
        return "high"
    return None


def parabola_peak(omega, values) -> tuple[float, float, int]:
    """Return the peak of a sampled curve: its frequency, its value and the largest sample.

    A parabola through the largest sample and its two neighbours places the peak between
    them, when the three frequencies increase, the parabola opens downwards and its vertex
    lies between the neighbours; otherwise the largest sample is the peak.

    Parameters
    ----------
    omega : array_like, shape (K,)
        Frequencies [rad/s].
    values : array_like, shape (K,)
        Real values (e.g. a compliance magnitude [m/N]).

    Returns
    -------
    omega_peak : float
        Frequency of the peak [rad/s].
    peak : float
        The peak (the parabola's vertex value, or the largest sample).
    index : int
        Index of the largest sample.
    """
    w = np.asarray(omega, dtype=float)
    c = np.asarray(values, dtype=float)
    i = int(np.argmax(c))
    if 0 < i < c.size - 1 and w[i - 1] < w[i] < w[i + 1]:
        c2, c1, c0 = np.polyfit(w[i - 1:i + 2] - w[i], c[i - 1:i + 2], 2)
        if c2 < 0:
            dx = -c1 / (2 * c2)
            if w[i - 1] - w[i] <= dx <= w[i + 1] - w[i]:
                return float(w[i] + dx), float(c0 - c1 * c1 / (4 * c2)), i
    return float(w[i]), float(c[i]), i


@dataclass(frozen=True)
class BandPeak:
    """The largest value of a curve over a band, and whether it is a resonance.

    Attributes
    ----------
    band : (float, float)
        The band searched [rad/s]: the first and the last frequency of the samples.
    largest : float
        The largest value in the band (refined between samples when inside).
    largest_frequency : float
        Where it lies [rad/s].
    edge : str or None
        ``"low"`` or ``"high"`` when the largest value is the band's first or last sample
        (:func:`extreme_edge`): then it is no resonance; None when it lies inside.
    resonance : float or None
        The resonance [rad/s]: ``largest_frequency`` when inside the band, else None.
    peak : float or None
        The value at the resonance, else None.
    inner_resonance, inner_peak : float or None
        When the largest value is at an edge: the largest local maximum strictly inside the
        band (lower than the edge value) [rad/s] and its value; None when there is none or
        the largest value is inside.
    rigid_body : bool
        The system has a rigid-body mode (0 Hz) that moves the point: a largest value at the
        lower edge then belongs to it, and no band can hold it.
    unit : str
        The unit of the values, for the text (e.g. ``"m/N"``).
    """

    band: tuple[float, float]
    largest: float
    largest_frequency: float
    edge: str | None
    resonance: float | None
    peak: float | None
    inner_resonance: float | None = None
    inner_peak: float | None = None
    rigid_body: bool = False
    unit: str = ""

    def __post_init__(self) -> None:
        if self.edge not in (None, *_EDGES):
            raise ValueError(f"BandPeak.edge must be None, 'low' or 'high', got {self.edge!r}")

    @property
    def band_hz(self) -> tuple[float, float]:
        """The band [Hz]."""
        return (self.band[0] * HZ_PER_RAD_S, self.band[1] * HZ_PER_RAD_S)

    def to_dict(self, name: str = "value") -> dict:
        """Return the peak as JSON-ready values (frequencies in Hz).

        Parameters
        ----------
        name : str
            The quantity and its unit in snake case, e.g. ``"compliance_m_per_n"``: it names
            the value keys (``peak_<name>``, ``largest_<name>``, ``inner_peak_<name>``).

        Returns
        -------
        dict
            ``band_hz``, ``peak_at_band_edge`` (``"low"``, ``"high"`` or None),
            ``resonance_hz`` and ``peak_<name>`` (None at an edge), ``largest_<name>`` and
            ``largest_at_hz`` (always), ``inner_resonance_hz`` and ``inner_peak_<name>``, and
            ``rigid_body_mode``.
        """
        def hz(w):
            return None if w is None else w * HZ_PER_RAD_S

        return {"band_hz": list(self.band_hz), "peak_at_band_edge": self.edge,
                "resonance_hz": hz(self.resonance), f"peak_{name}": self.peak,
                f"largest_{name}": self.largest,
                "largest_at_hz": self.largest_frequency * HZ_PER_RAD_S,
                "inner_resonance_hz": hz(self.inner_resonance),
                f"inner_peak_{name}": self.inner_peak,
                "rigid_body_mode": self.rigid_body}

    def describe(self, widen_low: str = "widen the band", widen_high: str = "widen the band"
                 ) -> str:
        """Return one line: the resonance, or why the largest value at an edge is none.

        Parameters
        ----------
        widen_low, widen_high : str
            How to widen the band below or above (e.g. ``"widen the band (--f-end-hz)"``).

        Returns
        -------
        str
            ``"resonance 111.8 Hz, peak 9.2e-08 m/N"`` inside the band; at an edge, which edge,
            that no resonance was found inside the band (or the largest one inside, lower than
            the edge value), that the response still rises there and how to widen the band; at
            the lower edge of a system with a rigid-body mode, that no band can hold that mode.
        """
        unit = f" {self.unit}" if self.unit else ""
        lo, hi = _hz(self.band[0]), _hz(self.band[1])
        if self.edge is None:
            return f"resonance {self.resonance * HZ_PER_RAD_S:.2f} Hz, peak {self.peak:.3g}{unit}"
        side = "lower" if self.edge == "low" else "upper"
        at = f"the largest value, {self.largest:.3g}{unit}, is at the band's {side} edge " \
             f"{_hz(self.largest_frequency)} Hz"
        inside = (f"no resonance found inside {lo}-{hi} Hz" if self.inner_resonance is None
                  else f"the largest resonance inside {lo}-{hi} Hz, {self.inner_peak:.3g}{unit} "
                       f"at {self.inner_resonance * HZ_PER_RAD_S:.2f} Hz, is lower")
        if self.edge == "low" and self.rigid_body:
            return (f"{at}: a rigid-body mode (0 Hz) moves the work piece, its compliance grows "
                    f"without bound towards 0 Hz and no band can hold it; {inside}")
        rises = "there" if self.edge == "high" else "below it"
        return (f"{at}: {inside}; the response still rises {rises}; "
                f"{widen_low if self.edge == 'low' else widen_high}")


def _default_refine(omega, values):
    w, p, _ = parabola_peak(omega, values)
    return w, p


def band_peak(omega, values, band=None, refine=None, rigid_body: bool = False,
              unit: str = "") -> BandPeak:
    """Return the largest value of a sampled curve over a band, and whether it is a resonance.

    Parameters
    ----------
    omega : array_like, shape (K,)
        Frequencies [rad/s], increasing.
    values : array_like, shape (K,)
        The curve (complex or real; its magnitude is taken).
    band : (float, float), optional
        The band [rad/s]; the samples inside it are searched (default: all).
    refine : callable, optional
        ``refine(omega, magnitude) -> (omega_peak, peak)``, called on the samples in the band
        (and on three samples around a local maximum) to place a maximum between samples;
        default :func:`parabola_peak`.
    rigid_body : bool
        The system has a rigid-body mode that moves the point (see :class:`BandPeak`).
    unit : str
        The unit of the values, for :meth:`BandPeak.describe`.

    Returns
    -------
    BandPeak
        The largest value, its edge (if any) and the resonance (None at an edge).

    Raises
    ------
    ValueError
        If no sample lies in the band, or no sample there is finite.

    See Also
    --------
    extreme_edge : the rule for the edge.

    Notes
    -----
    A maximum at the first or last sample of the band is at that edge, whatever the grid:
    with the samples alone nobody can tell a resonance just inside the edge from a response
    that keeps rising beyond it, and a finer grid or a wider band settles it.
    """
    omega = np.asarray(omega, dtype=float).reshape(-1)
    mag = np.abs(np.asarray(values)).reshape(-1)
    if omega.shape != mag.shape:
        raise ValueError(f"omega has {omega.size} samples and values {mag.size}")
    if band is not None:
        sel = (omega >= band[0]) & (omega <= band[1])
        omega, mag = omega[sel], mag[sel]
    finite = np.isfinite(mag)
    if not finite.any():
        raise ValueError("no finite sample in the band: no peak to report")
    refine = refine or _default_refine
    edge = extreme_edge(mag)
    last = int(np.flatnonzero(finite)[-1])
    span = (float(omega[0]), float(omega[-1]))
    kw = {"band": span, "rigid_body": bool(rigid_body), "unit": unit}
    if edge is None:
        w, p = refine(omega[:last + 1], mag[:last + 1])
        return BandPeak(largest=float(p), largest_frequency=float(w), edge=None,
                        resonance=float(w), peak=float(p), **kw)
    i = 0 if edge == "low" else mag.size - 1
    inner_w = inner_p = None
    m = np.where(finite, mag, -np.inf)
    mid, left, right = m[1:-1], m[:-2], m[2:]
    local = np.flatnonzero((mid >= left) & (mid >= right) & (mid > np.minimum(left, right))) + 1
    if local.size:
        j = int(local[np.argmax(m[local])])
        inner_w, inner_p = (float(x) for x in refine(omega[j - 1:j + 2], mag[j - 1:j + 2]))
    return BandPeak(largest=float(mag[i]), largest_frequency=float(omega[i]), edge=edge,
                    resonance=None, peak=None, inner_resonance=inner_w, inner_peak=inner_p,
                    **kw)


def rigid_body_moves(model, dof: str) -> bool:
    """Return whether a structure has a rigid-body mode (0 Hz) that moves a DOF.

    Parameters
    ----------
    model : servotune.structure.model.ModalModel
        The structure (in the configuration analysed).
    dof : str
        The DOF, e.g. ``"wp.x"``.

    Returns
    -------
    bool
        True when a mode of zero frequency has a mode-shape entry at ``dof`` above 1e-6 of
        the mode's largest entry.
    """
    omega = model.natural_frequencies()
    if not np.any(omega == 0.0):
        return False
    phi = model.mode_shapes()
    k = list(model.dofs).index(dof)
    for j in np.flatnonzero(omega == 0.0):
        col = np.abs(phi[:, j])
        if col[k] > 1e-6 * col.max():
            return True
    return False


def structure_peak(model, dof: str, band, n: int = 2000) -> BandPeak:
    """Return the largest driving-point receptance |X/F| of a structure at a DOF over a band.

    Parameters
    ----------
    model : servotune.structure.model.ModalModel
        The structure (in the configuration analysed).
    dof : str
        The DOF (force and displacement), e.g. ``"wp.x"``.
    band : (float, float)
        The band [rad/s], ``0 < low < high``.
    n : int
        Points of the logarithmic grid (default 2000); a maximum inside is refined by
        :meth:`~servotune.structure.model.ModalModel.compliance_peak`.

    Returns
    -------
    BandPeak
        In m/N, with ``rigid_body`` from :func:`rigid_body_moves`.

    Raises
    ------
    ValueError
        When the band is not ``0 < low < high``.

    Examples
    --------
    A 1000 kg slide on a 4e7 N/m spring (200 rad/s, 3 % damping): below the mode the largest
    value is at the band's upper edge; over a band that holds it, the resonance is found:

    >>> from servotune.structure.model import ModalModel
    >>> slide = ModalModel([[1000.0]], [[4e7]], ["slide.x"])
    >>> structure_peak(slide, "slide.x", (10.0, 150.0)).edge
    'high'
    >>> round(structure_peak(slide, "slide.x", (100.0, 400.0)).resonance / 200.0, 3)
    0.999
    """
    lo, hi = float(band[0]), float(band[1])
    if not 0 < lo < hi:
        raise ValueError(f"need 0 < low < high, got the band {lo!r}, {hi!r} rad/s")
    grid = np.geomspace(lo, hi, n)
    mag = np.abs(model.port_receptance(grid, [dof], [dof])[:, 0, 0])

    def refine(w, _):
        return model.compliance_peak(dof, float(w[0]), float(w[-1]))

    return band_peak(grid, mag, refine=refine, rigid_body=rigid_body_moves(model, dof),
                     unit="m/N")


@dataclass(frozen=True)
class ModeBand:
    """A default analysis band: a requirement band widened to hold the work-piece modes.

    Attributes
    ----------
    band : (float, float)
        The band [rad/s].
    requirement : (float, float)
        The band it was made from [rad/s].
    modes : tuple of float
        The natural frequencies [rad/s] of the modes that move the work piece significantly
        (flexible modes only; ascending; of modes within 1 % of each other, in different
        configurations, the lowest is listed).
    margin : float
        The room given to each mode (``f / margin`` to ``margin f``).
    """

    band: tuple[float, float]
    requirement: tuple[float, float]
    modes: tuple[float, ...]
    margin: float = BAND_MARGIN

    @property
    def widened(self) -> bool:
        """Whether the band is wider than the requirement band."""
        return self.band[0] < self.requirement[0] or self.band[1] > self.requirement[1]

    @property
    def band_hz(self) -> tuple[float, float]:
        """The band [Hz]."""
        return (self.band[0] * HZ_PER_RAD_S, self.band[1] * HZ_PER_RAD_S)

    def note(self, source: str = "[requirements] band_hz") -> str:
        """Return one line saying where the band comes from.

        Parameters
        ----------
        source : str
            What the requirement band is, e.g. ``"[requirements] band_hz"``.

        Returns
        -------
        str
            The band, its source, the work-piece modes and whether it was widened for them.
        """
        lo, hi = _hz(self.band[0]), _hz(self.band[1])
        modes = ", ".join(f"{w * HZ_PER_RAD_S:.1f}" for w in self.modes)
        held = (f"the work-piece modes at {modes} Hz" if self.modes
                else "no flexible mode that moves the work piece")
        if self.widened:
            return (f"band {lo}-{hi} Hz: {source} {_hz(self.requirement[0])}-"
                    f"{_hz(self.requirement[1])} Hz widened to hold {held} (x{self.margin:g} "
                    "margin)")
        return f"band {lo}-{hi} Hz ({source}); it holds {held} with x{self.margin:g} margin"

    def to_dict(self) -> dict:
        """Return the band as JSON-ready values (Hz).

        Returns
        -------
        dict
            ``band_hz``, ``requirement_band_hz``, ``work_piece_modes_hz``, ``margin`` and
            ``widened``.
        """
        return {"band_hz": list(self.band_hz),
                "requirement_band_hz": [self.requirement[0] * HZ_PER_RAD_S,
                                        self.requirement[1] * HZ_PER_RAD_S],
                "work_piece_modes_hz": [w * HZ_PER_RAD_S for w in self.modes],
                "margin": self.margin, "widened": self.widened}


def mode_band(band, models, dof: str, margin: float = BAND_MARGIN,
              share_min: float = SIGNIFICANT_SHARE) -> ModeBand:
    """Return a band widened to hold the modes that move a DOF, with a margin.

    Parameters
    ----------
    band : (float, float)
        The band to start from [rad/s], ``0 < low < high`` (an axis' requirement band).
    models : sequence of servotune.structure.model.ModalModel
        The structure in the configurations it can be in (e.g. pads and motor held or free).
    dof : str
        The DOF, e.g. ``"wp.x"``.
    margin : float
        Room around each mode, > 1 (default :data:`BAND_MARGIN`).
    share_min : float
        Smallest share of the static compliance at ``dof`` of a mode that counts
        (:meth:`~servotune.structure.model.ModalModel.participation`; default
        :data:`SIGNIFICANT_SHARE`).

    Returns
    -------
    ModeBand
        ``[min(low, f_min / margin), max(high, margin f_max)]`` over the flexible modes that
        count. Rigid-body modes (0 Hz) are not among them: no band holds them.

    Raises
    ------
    ValueError
        If the band is not ``0 < low < high`` or ``margin`` is not > 1.

    Examples
    --------
    A 300 kg work piece on 1.2e8 N/m rings at 100.7 Hz: a 5-50 Hz requirement band becomes
    5-131 Hz:

    >>> from servotune.structure.model import ModalModel
    >>> wp = ModalModel([[300.0]], [[1.2e8]], ["wp.x"])
    >>> result = mode_band((2 * np.pi * 5, 2 * np.pi * 50), [wp], "wp.x")
    >>> [round(f) for f in result.band_hz], result.widened
    ([5, 131], True)
    """
    lo, hi = float(band[0]), float(band[1])
    if not 0 < lo < hi:
        raise ValueError(f"need 0 < low < high, got the band {lo!r}, {hi!r} rad/s")
    if not margin > 1:
        raise ValueError(f"the margin must be > 1, got {margin!r}")
    found = []
    for model in models:
        omega = model.natural_frequencies()
        share = model.participation(dof)
        found += [float(w) for w, s in zip(omega, share, strict=True) if w > 0 and s >= share_min]
    modes = []
    for w in sorted(found):
        if not modes or w > modes[-1] * 1.01:
            modes.append(w)
    new = (min([lo] + [w / margin for w in found]), max([hi] + [w * margin for w in found]))
    return ModeBand(band=new, requirement=(lo, hi), modes=tuple(modes), margin=float(margin))


def chosen_band(default: ModeBand, f_start_hz: float | None = None,
                f_end_hz: float | None = None) -> tuple[tuple[float, float], str]:
    """Return the band of an analysis: the default band, or the ends the user gave.

    Parameters
    ----------
    default : ModeBand
        The default band (:func:`mode_band`).
    f_start_hz, f_end_hz : float, optional
        The ends the user gave [Hz]; the default band's end stands in for one not given.

    Returns
    -------
    band : (float, float)
        The band [rad/s].
    note : str
        One line saying where it comes from (:meth:`ModeBand.note` for the default).

    Raises
    ------
    ValueError
        If the band is not ``0 < start < end``.
    """
    if f_start_hz is None and f_end_hz is None:
        return default.band, default.note()
    lo_hz, hi_hz = default.band_hz
    start = lo_hz if f_start_hz is None else float(f_start_hz)
    end = hi_hz if f_end_hz is None else float(f_end_hz)
    if not 0 < start < end:
        raise ValueError(f"band {start:g}-{end:g} Hz: the band needs 0 < start < end")
    note = (f"band {start:g}-{end:g} Hz as given (the default {lo_hz:.4g}-{hi_hz:.4g} Hz "
            "holds the work-piece modes)")
    return (start / HZ_PER_RAD_S, end / HZ_PER_RAD_S), note
