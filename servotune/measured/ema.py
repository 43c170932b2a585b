"""Experimental modal analysis of measured FRFs: poles by LSCF, residues by LSFD, chosen poles.

The problem: given FRFs H_i(omega) measured over a band (one or several response points, one
excitation), find the modes r (natural frequency omega_r, damping ratio zeta_r) and their
residues R_ir such that, over the band,

    H_i(j w) ~ sum_r [ R_ir / (j w - lambda_r) + conj(R_ir) / (j w - conj(lambda_r)) ]
               - LR_i / w^2 + UR_i                     (for a receptance)

with lambda_r = -zeta_r omega_r + j omega_r sqrt(1 - zeta_r^2) and the lower and upper residual
terms LR_i, UR_i standing for the modes below and above the band. For a mobility or an
accelerance the modal sum is multiplied by j w or (j w)^2; the residues R_ir are always those
of the receptance [m/(N s)].

The stages, each a named function:

1. :func:`pole_estimates`: the poles at every model order by the least-squares complex
   frequency-domain estimator (LSCF) [1]_ [2]_, as sdypy-EMA implements it [3]_
   (``Model.get_poles("lscf")``).
2. :func:`stabilisation_diagram` [1]_: each pole of each order compared with the nearest pole of
   the order below (:class:`SelectionRule`: within 1 % in frequency and 5 % in damping is
   stable), and how many consecutive orders it has stood for.
3. :func:`choose_poles`: the physical poles: a pole that stood, stable, over at least 5
   consecutive orders with a damping ratio in (0, 0.3) and a frequency in the band but not in
   its outer 3 % at either end (where the fit's edge effects turn noise into stable poles:
   widen the band to identify a mode there); such poles within 1 % of one another are one
   mode, represented by the pole nearest to their median frequency and damping. Or, when
   frequencies are given, the mode of the rule nearest to each.
4. The residues and the residual terms by least squares in the frequency domain (LSFD) on the
   chosen poles (sdypy-EMA's ``LSFD``), and the synthesised FRFs over the band.

:func:`identify_modes` runs them and returns a :class:`ModalIdentification`.

References
----------
.. [1] B. Peeters, H. Van der Auweraer, P. Guillaume, J. Leuridan, "The PolyMAX
   frequency-domain method: a new standard for modal parameter estimation?", Shock and
   Vibration 11 (2004) 395-409 (LSCF/PolyMAX, stabilisation diagrams, LSFD).
.. [2] P. Guillaume, P. Verboven, S. Vanlanduit, H. Van der Auweraer, B. Peeters, "A
   poly-reference implementation of the least-squares complex frequency-domain estimator",
   Proc. IMAC XXI (2003).
.. [3] sdypy-EMA, experimental and operational modal analysis (https://github.com/sdypy/sdypy-EMA):
   the LSCF and LSFD implementations used here.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..units import HZ_PER_RAD_S
from .frf import MeasuredFrf

__all__ = [
    "SelectionRule",
    "PoleEstimates",
    "StabilisationDiagram",
    "IdentifiedMode",
    "ModalIdentification",
    "check_frfs",
    "pole_estimates",
    "stabilisation_diagram",
    "choose_poles",
    "identify_modes",
    "STATUS_NAMES",
]

#: what the ``status`` of a pole in the stabilisation diagram means
STATUS_NAMES = {-1: "damping outside the accepted range", 0: "new",
                1: "stable in frequency", 2: "stable in frequency and damping"}


@dataclass(frozen=True)
class SelectionRule:
    """The rule that chooses the physical poles of a stabilisation diagram.

    Attributes
    ----------
    frequency_tolerance : float
        Largest relative change of the natural frequency from one model order to the next of
        a stable pole (default 0.01).
    damping_tolerance : float
        Largest relative change of the damping ratio (default 0.05).
    min_stable_orders : int
        Fewest consecutive model orders a pole must stand for, stable, to be physical
        (default 5).
    damping_range : tuple of float
        The open interval of damping ratios accepted (default (0, 0.3)).
    edge_margin : float
        Share of the band's width at either end where no pole is chosen by the rule
        (default 0.03): there the fit's edge effects make stable poles of noise.
    """

    frequency_tolerance: float = 0.01
    damping_tolerance: float = 0.05
    min_stable_orders: int = 5
    damping_range: tuple[float, float] = (0.0, 0.3)
    edge_margin: float = 0.03

    def __post_init__(self):
        for name in ("frequency_tolerance", "damping_tolerance"):
            value = getattr(self, name)
            if not (0 < value < 1):
                raise ValueError(f"SelectionRule.{name} must be in (0, 1), got {value!r}")
        if int(self.min_stable_orders) != self.min_stable_orders or self.min_stable_orders < 2:
            raise ValueError("SelectionRule.min_stable_orders must be a whole number >= 2, got "
                             f"{self.min_stable_orders!r}")
        low, high = (float(v) for v in self.damping_range)
        if not (0 <= low < high <= 1):
            raise ValueError("SelectionRule.damping_range must be (low, high) with "
                             f"0 <= low < high <= 1, got {self.damping_range!r}")
        object.__setattr__(self, "damping_range", (low, high))
        if not (0 <= self.edge_margin < 0.5):
            raise ValueError(f"SelectionRule.edge_margin must be in [0, 0.5), got "
                             f"{self.edge_margin!r}")

    def describe(self) -> str:
        """Return the rule in one sentence, for reports.

        Returns
        -------
        str
            The rule with its numbers.
        """
        low, high = self.damping_range
        return (f"a pole is physical when it stands over at least {self.min_stable_orders} "
                f"consecutive model orders within {100 * self.frequency_tolerance:g} % in "
                f"frequency and {100 * self.damping_tolerance:g} % in damping of the order "
                f"below, with a damping ratio in ({low:g}, {high:g}) and a frequency in the "
                f"band but not in its outer {100 * self.edge_margin:g} % at either end; such "
                f"poles within {100 * self.frequency_tolerance:g} % of one another "
                "are one mode, represented by the pole nearest to their median frequency and "
                "damping")

    def to_dict(self) -> dict:
        """Return the rule's numbers and its sentence.

        Returns
        -------
        dict
            The fields and ``text``.
        """
        return {"frequency_tolerance": self.frequency_tolerance,
                "damping_tolerance": self.damping_tolerance,
                "min_stable_orders": int(self.min_stable_orders),
                "damping_range": list(self.damping_range), "edge_margin": self.edge_margin,
                "text": self.describe()}


@dataclass(frozen=True)
class PoleEstimates:
    """The poles of every model order over a band (stage 1).

    Attributes
    ----------
    orders : tuple of int
        The model orders (the degree of the denominator polynomial: 2, 4, ...).
    poles : tuple of numpy.ndarray
        The complex poles [rad/s] of each order, those with a positive imaginary part.
    band : tuple of float
        The band fitted [rad/s].
    """

    orders: tuple[int, ...]
    poles: tuple[np.ndarray, ...]
    band: tuple[float, float]


@dataclass(frozen=True)
class StabilisationDiagram:
    """Every pole in the band at every model order, with its stability (stage 2).

    Attributes
    ----------
    order : numpy.ndarray
        Model order of each pole (int).
    pole : numpy.ndarray
        The complex pole [rad/s].
    frequency : numpy.ndarray
        Natural frequency |pole| [rad/s].
    damping_ratio : numpy.ndarray
        -Re(pole) / |pole|.
    status : numpy.ndarray
        :data:`STATUS_NAMES`: -1 damping outside the range, 0 new, 1 stable in frequency,
        2 stable in frequency and damping.
    run : numpy.ndarray
        Consecutive orders the pole has stood for, stable, up to its own (1 for a new one).
    band : tuple of float
        The band [rad/s].
    rule : SelectionRule
        The rule the status and runs follow.
    """

    order: np.ndarray
    pole: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    status: np.ndarray
    run: np.ndarray
    band: tuple[float, float]
    rule: SelectionRule

    def physical(self, edges: bool = True) -> np.ndarray:
        """Return the indices of the poles that meet the rule (stable long enough, off the edges).

        Parameters
        ----------
        edges : bool
            Leave out the poles in the rule's margins at the band's edges (default); False
            keeps them (for poles picked by frequency).

        Returns
        -------
        numpy.ndarray
            Indices into the arrays of the diagram.
        """
        low, high = self.band
        margin = self.rule.edge_margin * (high - low) if edges else 0.0
        inside = (self.frequency >= low + margin) & (self.frequency <= high - margin)
        return np.flatnonzero((self.status == 2) & (self.run >= self.rule.min_stable_orders)
                              & inside)


@dataclass(frozen=True)
class IdentifiedMode:
    """One identified mode.

    Attributes
    ----------
    frequency : float
        Natural frequency |lambda| [rad/s].
    damping_ratio : float
        -Re(lambda) / |lambda|.
    pole : complex
        lambda [rad/s], positive imaginary part.
    residues : numpy.ndarray
        The receptance residue R of each FRF [m/(N s)] (complex; see the module's equation).
    order : int
        The model order the chosen pole comes from.
    stable_orders : int
        The consecutive orders it stood for, stable (below the rule's minimum only for a pole
        chosen by frequency).
    requested : float or None
        The frequency asked for [rad/s] when the mode was chosen by frequency.
    """

    frequency: float
    damping_ratio: float
    pole: complex
    residues: np.ndarray
    order: int
    stable_orders: int
    requested: float | None = None

    def to_dict(self) -> dict:
        """Return the mode with edge units (Hz) and complex numbers as [re, im].

        Returns
        -------
        dict
            ``frequency_hz``, ``damping_ratio``, ``residue`` (of the first FRF), ``residues``
            (one per FRF), ``pole``, ``model_order``, ``stable_orders``, ``requested_hz``.
        """
        pairs = [[float(r.real), float(r.imag)] for r in self.residues]
        return {"frequency_hz": self.frequency * HZ_PER_RAD_S,
                "damping_ratio": self.damping_ratio, "residue": pairs[0], "residues": pairs,
                "pole": [float(self.pole.real), float(self.pole.imag)],
                "model_order": int(self.order), "stable_orders": int(self.stable_orders),
                "requested_hz": (None if self.requested is None
                                 else self.requested * HZ_PER_RAD_S)}


@dataclass(frozen=True)
class ModalIdentification:
    """The modes identified from measured FRFs, and how well they reproduce them.

    Attributes
    ----------
    modes : tuple of IdentifiedMode
        By increasing frequency.
    frfs : tuple of MeasuredFrf
        The measurements.
    omega : numpy.ndarray
        The frequencies of the band [rad/s] where the residues were fitted.
    measured : numpy.ndarray
        The measured FRFs over ``omega`` (one row per FRF, SI).
    synthesised : numpy.ndarray
        The FRFs of the modes and residual terms over ``omega``.
    frf_error : float
        Relative RMS error over the band and all FRFs:
        sqrt(sum |H_syn - H|^2 / sum |H|^2).
    frf_errors : tuple of float
        The same per FRF.
    lower_residuals, upper_residuals : numpy.ndarray
        The residual terms of each FRF (LR, UR of the module's equation, for a receptance).
    diagram : StabilisationDiagram
        Every pole of every order.
    max_order : int
        The highest model order fitted.
    chosen_by : str
        ``"rule"`` (automatic) or ``"frequency"`` (the poles nearest to given frequencies).
    method : str
        The methods and their implementation.
    defaults : tuple of str
        What was assumed (a default band, the quantity or units of a file).
    notes : tuple of str
        Other remarks.
    warnings : tuple of str
        What makes the result doubtful.
    """

    modes: tuple[IdentifiedMode, ...]
    frfs: tuple[MeasuredFrf, ...]
    omega: np.ndarray
    measured: np.ndarray
    synthesised: np.ndarray
    frf_error: float
    frf_errors: tuple[float, ...]
    lower_residuals: np.ndarray
    upper_residuals: np.ndarray
    diagram: StabilisationDiagram
    max_order: int
    chosen_by: str
    method: str
    defaults: tuple[str, ...] = field(default=())
    notes: tuple[str, ...] = field(default=())
    warnings: tuple[str, ...] = field(default=())

    @property
    def band(self) -> tuple[float, float]:
        """The band fitted [rad/s]: the first and last frequency of ``omega``."""
        return float(self.omega[0]), float(self.omega[-1])

    def to_dict(self) -> dict:
        """Return the results in SI with edge units in the names.

        Returns
        -------
        dict
            ``modes``, ``frf_error``, ``frf_errors``, ``frfs``, ``quantity``, ``band_hz``,
            ``max_order``, ``chosen_by``, ``selection_rule``, ``method``, ``defaults_taken``,
            ``notes`` (the defaults taken and the other remarks), ``warnings``.
        """
        return {
            "modes": [m.to_dict() for m in self.modes],
            "frf_error": self.frf_error,
            "frf_errors": list(self.frf_errors),
            "frfs": [f.to_dict() for f in self.frfs],
            "quantity": self.frfs[0].quantity,
            "band_hz": [self.band[0] * HZ_PER_RAD_S, self.band[1] * HZ_PER_RAD_S],
            "max_order": self.max_order,
            "chosen_by": self.chosen_by,
            "selection_rule": self.diagram.rule.to_dict(),
            "method": self.method,
            "defaults_taken": list(self.defaults),
            "notes": [*self.defaults, *self.notes],
            "warnings": list(self.warnings),
        }

    def plot_fit(self):
        """Return the figure of the measured against the synthesised FRFs.

        Returns
        -------
        matplotlib.figure.Figure
            See :func:`servotune.measured.figures.plot_frf_fit`.
        """
        from .figures import plot_frf_fit

        return plot_frf_fit(self)

    def plot_stabilisation(self):
        """Return the stabilisation diagram.

        Returns
        -------
        matplotlib.figure.Figure
            See :func:`servotune.measured.figures.plot_stabilisation`.
        """
        from .figures import plot_stabilisation

        return plot_stabilisation(self)


def check_frfs(frfs) -> tuple[np.ndarray, np.ndarray, str]:
    """Check that FRFs can be fitted together; return their common grid.

    LSCF works on evenly spaced frequency lines from 0 Hz (its discrete-time model), and one
    fit takes one quantity: all FRFs must share the frequencies and the quantity.

    Parameters
    ----------
    frfs : sequence of MeasuredFrf
        The measurements.

    Returns
    -------
    omega : numpy.ndarray
        The common frequencies [rad/s].
    values : numpy.ndarray
        The FRFs, one row each.
    quantity : str
        Their quantity.

    Raises
    ------
    ValueError
        Naming the FRFs that differ and the fix.
    """
    frfs = tuple(frfs)
    if not frfs:
        raise ValueError("no FRF to identify modes from: give at least one file")
    first = frfs[0]
    for other in frfs[1:]:
        if other.quantity != first.quantity:
            raise ValueError(f"{other.name} is a {other.quantity} but {first.name} a "
                             f"{first.quantity}: identify one quantity at a time")
        if other.omega.shape != first.omega.shape or not np.allclose(
                other.omega, first.omega, rtol=1e-9, atol=0):
            raise ValueError(f"{other.name} and {first.name} have different frequency lines: "
                             "export every FRF of one identification on the same lines")
    omega = first.omega
    step = np.diff(omega)
    df = step[0]
    if not np.allclose(step, df, rtol=1e-6, atol=0):
        i = int(np.argmax(np.abs(step - df)))
        raise ValueError(f"{first.name}: the frequency lines are not evenly spaced (step "
                         f"{df * HZ_PER_RAD_S:g} Hz, then {step[i] * HZ_PER_RAD_S:g} Hz at "
                         f"{omega[i] * HZ_PER_RAD_S:g} Hz); LSCF needs evenly spaced lines: "
                         "export the FRF as measured, without resampling or gaps")
    start = omega[0] / df
    if abs(start - round(start)) > 1e-6:
        raise ValueError(f"{first.name}: the first line {omega[0] * HZ_PER_RAD_S:g} Hz is not "
                         f"a whole multiple of the step {df * HZ_PER_RAD_S:g} Hz; LSCF needs "
                         "the lines k * df: export the FRF on its measured lines")
    return omega, np.array([f.values for f in frfs]), first.quantity


def _band_indices(omega: np.ndarray, band, label: str
                  ) -> tuple[int, int, list[str], list[str]]:
    """The first and last index of the band on the grid; the default taken, the notes;
    errors start with ``label`` (the measurement)."""
    defaults, notes = [], []
    positive = np.flatnonzero(omega > 0)
    f_hz = omega * HZ_PER_RAD_S
    if band is None:
        lo_i, hi_i = int(positive[0]), omega.size - 1
        defaults.append(f"band {f_hz[lo_i]:g}-{f_hz[hi_i]:g} Hz, the whole measurement above "
                        "0 Hz (no --band-hz)")
    else:
        lo, hi = (float(b) for b in band)
        given = f"{label}: the band {lo * HZ_PER_RAD_S:g}-{hi * HZ_PER_RAD_S:g} Hz"
        if not (0 < lo < hi):
            raise ValueError(f"{given} must have 0 < low < high")
        if lo > omega[-1] or hi < omega[positive[0]]:
            raise ValueError(f"{given} lies "
                             f"outside the measurement ({f_hz[positive[0]]:g}-{f_hz[-1]:g} "
                             "Hz): give a band inside it")
        lo_i = int(np.flatnonzero(omega >= lo * (1 - 1e-12))[0])
        hi_i = int(np.flatnonzero(omega <= hi * (1 + 1e-12))[-1])
        lo_i = max(lo_i, int(positive[0]))
        if lo * (1 - 1e-9) < omega[positive[0]] or hi * (1 + 1e-9) > omega[-1]:
            notes.append(f"band cut to the measurement: {f_hz[lo_i]:g}-{f_hz[hi_i]:g} Hz")
    if hi_i - lo_i < 8:
        raise ValueError(f"{label}: the band {f_hz[lo_i]:g}-{f_hz[hi_i]:g} Hz holds "
                         f"{hi_i - lo_i + 1} frequency line(s); give a wider band or a finer "
                         "measurement (at least 9 lines)")
    return lo_i, hi_i, defaults, notes


def pole_estimates(omega, values, quantity: str, band, max_order: int) -> PoleEstimates:
    """Estimate the poles at model orders 2, 4, ..., 2 ``max_order`` by LSCF (sdypy-EMA).

    Parameters
    ----------
    omega : numpy.ndarray
        Evenly spaced frequencies k * d omega [rad/s] (see :func:`check_frfs`).
    values : numpy.ndarray
        The FRFs, one row each, SI.
    quantity : str
        ``"receptance"``, ``"mobility"`` or ``"accelerance"``.
    band : tuple of float
        The band (low, high) [rad/s] on the grid.
    max_order : int
        Number of model orders (the highest denominator degree is twice it).

    Returns
    -------
    PoleEstimates
        The poles of each order with a positive imaginary part.
    """
    from sdypy.EMA import Model

    f_hz = np.asarray(omega) * HZ_PER_RAD_S
    lo_hz, hi_hz = band[0] * HZ_PER_RAD_S, band[1] * HZ_PER_RAD_S
    hi_i = int(np.argmin(np.abs(f_hz - hi_hz)))
    end = min(hi_i + 1, f_hz.size - 1)  # sdypy keeps the lines below `upper`
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = Model(frf=np.asarray(values)[:, :end + 1], freq=f_hz[:end + 1], lower=lo_hz,
                      upper=f_hz[end], pol_order_high=int(max_order), frf_form=quantity)
        model.get_poles(method="lscf", show_progress=False)
    poles = []
    for p in model.all_poles:
        p = np.asarray(p, dtype=complex)
        poles.append(p[np.isfinite(p) & (p.imag > 0)])
    orders = tuple(2 * (k + 1) for k in range(len(poles)))
    return PoleEstimates(orders, tuple(poles), (float(band[0]), float(band[1])))


def stabilisation_diagram(estimates: PoleEstimates,
                          rule: SelectionRule = SelectionRule()) -> StabilisationDiagram:
    """Compare each pole with the poles of the order below: the stabilisation diagram.

    Parameters
    ----------
    estimates : PoleEstimates
        The poles of every order.
    rule : SelectionRule
        Tolerances and the damping range.

    Returns
    -------
    StabilisationDiagram
        The poles in the band with their status and run of stable orders.

    Notes
    -----
    A pole p of order n with a damping ratio in the rule's range is matched with the pole q of
    order n - 2 (the order below) in that range that is nearest in frequency; it is stable in
    frequency when |w_p - w_q| <= tol_f w_q, stable when also |zeta_p - zeta_q| <= tol_zeta
    zeta_q (Peeters et al. 2004, see the module). Its run is the run of q plus one when
    stable, else 1.
    """
    low, high = estimates.band
    zmin, zmax = rule.damping_range
    rows = []  # (order, pole, w, zeta, status, run)
    previous = None  # (w, zeta, run) of the plausible poles of the order below
    for order, poles in zip(estimates.orders, estimates.poles, strict=True):
        w = np.abs(poles)
        zeta = -poles.real / np.where(w > 0, w, np.inf)
        inside = (w >= low) & (w <= high)
        plausible = inside & (zeta > zmin) & (zeta < zmax)
        current_w, current_z, current_run = [], [], []
        for k in np.flatnonzero(inside):
            if not plausible[k]:
                rows.append((order, poles[k], w[k], zeta[k], -1, 0))
                continue
            status, run = 0, 1
            if previous is not None and previous[0].size:
                pw, pz, prun = previous
                df = np.abs(w[k] - pw) / pw
                dz = np.abs(zeta[k] - pz) / pz
                both = (df <= rule.frequency_tolerance) & (dz <= rule.damping_tolerance)
                if both.any():
                    j = np.flatnonzero(both)[np.argmin(df[both])]
                    status, run = 2, int(prun[j]) + 1
                elif (df <= rule.frequency_tolerance).any():
                    status = 1
            rows.append((order, poles[k], w[k], zeta[k], status, run))
            current_w.append(w[k])
            current_z.append(zeta[k])
            current_run.append(run)
        previous = (np.array(current_w), np.array(current_z), np.array(current_run))
    if rows:
        order, pole, w, zeta, status, run = (np.array(c) for c in zip(*rows, strict=True))
    else:
        order, status, run = (np.zeros(0, int) for _ in range(3))
        pole, w, zeta = np.zeros(0, complex), np.zeros(0), np.zeros(0)
    return StabilisationDiagram(order.astype(int), pole.astype(complex), w.astype(float),
                                zeta.astype(float), status.astype(int), run.astype(int),
                                estimates.band, rule)


def _groups(diagram: StabilisationDiagram, edges: bool = True) -> list[np.ndarray]:
    """The physical poles grouped into modes (neighbours in frequency within tol_f)."""
    idx = diagram.physical(edges)
    if not idx.size:
        return []
    idx = idx[np.argsort(diagram.frequency[idx])]
    w = diagram.frequency[idx]
    cuts = np.flatnonzero(np.diff(w) > diagram.rule.frequency_tolerance * w[:-1]) + 1
    return [g for g in np.split(idx, cuts) if g.size]


def _representative(diagram: StabilisationDiagram, group: np.ndarray) -> int:
    rule = diagram.rule
    w, z = diagram.frequency[group], diagram.damping_ratio[group]
    wm, zm = np.median(w), np.median(z)
    distance = (((w - wm) / (wm * rule.frequency_tolerance)) ** 2
                + ((z - zm) / (zm * rule.damping_tolerance)) ** 2)
    return int(group[np.argmin(distance)])


def choose_poles(diagram: StabilisationDiagram, frequencies=None
                 ) -> tuple[list[int], list[str]]:
    """Choose the physical poles of a stabilisation diagram.

    Parameters
    ----------
    diagram : StabilisationDiagram
        The poles with their status.
    frequencies : sequence of float, optional
        Natural frequencies [rad/s] to pick the nearest poles for, instead of the rule: the
        nearest mode of the rule (the band's edge margins included), or, where the rule finds
        none, the nearest pole of the highest orders with a damping ratio in the range.

    Returns
    -------
    indices : list of int
        Indices into the diagram of the chosen poles, by increasing frequency.
    warnings : list of str
        Picks far (more than 5 %) from the frequency asked for.

    Raises
    ------
    ValueError
        When the rule finds no pole, when there is no pole to pick, or when two frequencies
        pick the same pole.
    """
    groups = _groups(diagram, edges=frequencies is None)
    chosen = [_representative(diagram, g) for g in groups]
    if frequencies is None:
        if not chosen:
            raise ValueError(
                "no pole stands over the orders the rule asks for ("
                + diagram.rule.describe() + "); give a larger --max-order, a narrower "
                "--band-hz around the resonances, or the frequencies with --modes-hz")
        return sorted(chosen, key=lambda i: diagram.frequency[i]), []
    notes = []
    candidates = np.array(chosen, dtype=int)
    if not candidates.size:
        plausible = np.flatnonzero(diagram.status >= 0)
        if not plausible.size:
            raise ValueError("no pole with a damping ratio in the accepted range lies in the "
                             "band: widen --band-hz or raise --max-order")
        top = diagram.order[plausible].max()
        candidates = plausible[diagram.order[plausible] >= top - 4]
        notes.append("no pole meets the rule; the poles of the highest orders were picked by "
                     "frequency")
    picked = []
    for f in frequencies:
        i = int(candidates[np.argmin(np.abs(diagram.frequency[candidates] - f))])
        if i in picked:
            raise ValueError(
                f"{f * HZ_PER_RAD_S:g} Hz and another frequency given pick the same pole at "
                f"{diagram.frequency[i] * HZ_PER_RAD_S:.4g} Hz; give the frequencies of "
                "distinct modes")
        if abs(diagram.frequency[i] - f) > 0.05 * f:
            notes.append(f"the pole nearest to {f * HZ_PER_RAD_S:g} Hz is at "
                         f"{diagram.frequency[i] * HZ_PER_RAD_S:.4g} Hz, more than 5 % away")
        picked.append(i)
    return picked, notes


def _residues(omega, values, quantity: str, poles: np.ndarray):
    """LSFD (sdypy-EMA) on the chosen poles over the band: residues, residuals, synthesis."""
    from sdypy.EMA.EMA import LSFD

    f_hz = np.asarray(omega) * HZ_PER_RAD_S
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        residues, synthesised, lower, upper = LSFD(
            np.asarray(poles, dtype=complex), np.asarray(values), f_hz, True, True, 0,
            f_hz.size, quantity)
    return (np.asarray(residues), np.asarray(synthesised), np.asarray(lower),
            np.asarray(upper))


def identify_modes(frfs, band=None, max_order: int = 40, frequencies=None,
                   rule: SelectionRule = SelectionRule()) -> ModalIdentification:
    """Identify natural frequencies, damping ratios and residues from measured FRFs.

    Parameters
    ----------
    frfs : sequence of MeasuredFrf
        One or several FRFs of one quantity on the same evenly spaced frequency lines (one
        excitation, several responses).
    band : tuple of float, optional
        (low, high) [rad/s]; default the whole measurement above 0.
    max_order : int
        Number of model orders of LSCF (denominator degrees 2 to 2 ``max_order``), default 40.
    frequencies : sequence of float, optional
        Natural frequencies [rad/s] whose nearest poles are taken instead of the rule's.
    rule : SelectionRule
        The rule that chooses the physical poles.

    Returns
    -------
    ModalIdentification
        The modes, the synthesised FRFs, the error, the stabilisation diagram.

    Raises
    ------
    ValueError
        FRFs that cannot be fitted together, a band outside the measurement, no physical pole.

    See Also
    --------
    servotune.measured.frf.read_frfs : reads the files.

    Notes
    -----
    Poles by LSCF (Peeters et al. 2004; Guillaume et al. 2003) and residues by LSFD with lower
    and upper residual terms (Peeters et al. 2004), as implemented in sdypy-EMA; the choice of
    poles by :func:`choose_poles`. The references are in :mod:`servotune.measured.ema`.

    Examples
    --------
    One mass on a spring and a damper, m = 1 kg, k = 1e6 N/m, c = 20 N s/m: the mode is
    at sqrt(k/m) = 1000 rad/s with zeta = c / (2 sqrt(k m)) = 0.01.

    >>> import numpy as np
    >>> from servotune.measured.frf import MeasuredFrf
    >>> w = 2 * np.pi * np.arange(0, 400, 0.5)
    >>> h = 1 / (1e6 - w**2 + 20j * w)
    >>> fit = identify_modes([MeasuredFrf(w, h, "receptance", "sdof", "sdof.csv")], max_order=20)
    >>> m = fit.modes[0]
    >>> round(m.frequency), round(m.damping_ratio, 4)
    (1000, 0.01)
    """
    frfs = tuple(frfs)
    omega, values, quantity = check_frfs(frfs)
    max_order = int(max_order)
    if max_order < rule.min_stable_orders:
        raise ValueError(f"max_order {max_order} is below the {rule.min_stable_orders} "
                         "consecutive orders the rule asks for; give a larger one")
    label = frfs[0].name + (f" and {len(frfs) - 1} more FRF(s)" if len(frfs) > 1 else "")
    lo_i, hi_i, defaults, notes = _band_indices(omega, band, label)
    estimates = pole_estimates(omega, values, quantity, (omega[lo_i], omega[hi_i]), max_order)
    diagram = stabilisation_diagram(estimates, rule)
    try:
        chosen, picks = choose_poles(diagram, frequencies)
    except ValueError as exc:
        raise ValueError(f"{label}: {exc}") from None
    order = sorted(range(len(chosen)), key=lambda k: diagram.frequency[chosen[k]])
    chosen = [chosen[k] for k in order]
    requested = (None if frequencies is None else [float(frequencies[k]) for k in order])
    poles = diagram.pole[chosen]
    grid = omega[lo_i:hi_i + 1]
    measured = values[:, lo_i:hi_i + 1]
    residues, synthesised, lower, upper = _residues(grid, measured, quantity, poles)
    misfit = np.abs(synthesised - measured) ** 2
    size = np.sum(np.abs(measured) ** 2, axis=1)
    errors = tuple(float(math.sqrt(e / s)) if s > 0 else math.inf
                   for e, s in zip(misfit.sum(axis=1), size, strict=True))
    total = float(math.sqrt(misfit.sum() / size.sum())) if size.sum() > 0 else math.inf
    modes = tuple(
        IdentifiedMode(float(diagram.frequency[i]), float(diagram.damping_ratio[i]),
                       complex(diagram.pole[i]), residues[:, k].copy(), int(diagram.order[i]),
                       int(diagram.run[i]), None if requested is None else requested[k])
        for k, i in enumerate(chosen))
    for m in modes:
        m.residues.flags.writeable = False
    warn = list(picks)
    if total > 0.2:
        warn.append(f"the synthesised FRFs differ from the measurement by {100 * total:.0f} % "
                    "(relative RMS over the band): modes may be missing or spurious; look at "
                    "the stabilisation diagram")
    from sdypy.EMA import __version__ as ema_version

    method = (f"poles by LSCF, residues by LSFD with lower and upper residual terms "
              f"(sdypy-EMA {ema_version}; Peeters et al. 2004, Guillaume et al. 2003)")
    defaults = [*defaults, *(n for f in frfs for n in f.defaults)]
    notes = [*notes, *(n for f in frfs for n in f.notes)]
    return ModalIdentification(
        modes, frfs, grid, measured, synthesised, total, errors, lower, upper, diagram,
        max_order, "rule" if frequencies is None else "frequency", method, tuple(defaults),
        tuple(notes), tuple(warn))

