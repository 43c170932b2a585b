"""The tuning problem: design variables, bounds, objectives and requirements (SI)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from ..drive import Drive, LowPassFilter, NotchFilter, PIController
from ..regimes import RegimeModel
from ..requirements import Requirements
from ..structure.model import ModalModel
from ..thrust import ThrustBudget
from ..validation import positive

__all__ = ["LOWPASS_VARIABLES", "NOTCH_VARIABLES", "VARIABLES", "ChatterTarget", "Design",
           "NoStableStartError", "RequirementsNotMetError", "TuningDidNotConvergeError",
           "TuningProblem"]

VARIABLES = ("c", "kv", "kp", "ti", "notch_frequency", "notch_width", "notch_depth",
             "lowpass_frequency")
#: The tuned current set-point notch's variables (``"notch"`` in ``free`` names all three).
NOTCH_VARIABLES = ("notch_frequency", "notch_width", "notch_depth")
#: The tuned current set-point low-pass's variable (``"lowpass"`` in ``free`` names it): its
#: corner frequency; its damping ratio stays as given (1/sqrt 2 by default).
LOWPASS_VARIABLES = ("lowpass_frequency",)
#: The widest notch the tuner sets (relative -3 dB width, 2 zeta_p): one octave and a bit;
#: a wider one is a low-pass's job.
NOTCH_WIDTH_MAX = 1.0
#: SI units of the design variables.
UNITS = {"c": "N s/m", "kv": "1/s", "kp": "N m s/rad", "ti": "s", "notch_frequency": "rad/s",
         "notch_width": "-", "notch_depth": "-", "lowpass_frequency": "rad/s"}
#: Shorthands of ``free``: a filter's name for its variables.
FREE_SHORTHANDS = {"notch": NOTCH_VARIABLES, "lowpass": LOWPASS_VARIABLES}


def expand_free(free) -> tuple[str, ...]:
    """Return the free variables with the shorthands written out (``"notch"``: its three
    variables, frequency, width and depth; ``"lowpass"``: its corner frequency), in order and
    without repeats.

    Parameters
    ----------
    free : str or sequence of str
        Variable names (:data:`VARIABLES`, ``"notch"`` and ``"lowpass"``).

    Returns
    -------
    tuple of str

    Examples
    --------
    >>> expand_free(["c", "notch", "kv", "lowpass"])
    ('c', 'notch_frequency', 'notch_width', 'notch_depth', 'kv', 'lowpass_frequency')
    """
    out = []
    for v in ((free,) if isinstance(free, str) else free):
        out += list(FREE_SHORTHANDS.get(v, (v,)))
    return tuple(dict.fromkeys(out))


class RequirementsNotMetError(ValueError):
    """The requirements cannot be met within the bounds (names the binding constraint)."""


class NoStableStartError(ValueError):
    """No design near the initial one keeps every regime model stable: the tuning has nowhere to
    start (the message names the unstable models and what to change)."""


class TuningDidNotConvergeError(RuntimeError):
    """The optimiser stopped without a usable design while the requirements themselves were
    met (e.g. the iteration limit): more starts or narrower bounds are the remedy."""


@dataclass(frozen=True)
class ChatterTarget:
    """Chatter-limit objective in the oriented one-direction zero-order form.

    With only the feed direction flexible, the oriented FRF is ``Phi = mu G`` (G the work-piece
    compliance, mu the directional factor of the milling set-up) and the limiting depth is
    ``b_lim = -1 / (2 Kt Re Phi)`` at the chatter frequency; the absolute limit is
    ``b_crit = -1 / (2 Kt min_w Re Phi)`` (Tlusty; Altintas and Budak 1995; see
    :mod:`servotune.chatter.zoa`).

    Parameters
    ----------
    kt : float
        Tangential cutting coefficient [N/m^2] (> 0).
    mu : float
        Directional factor mu = D_xx/Kt [-] (non-zero; may be negative).
    required_depth : float, optional
        Required axial depth [m]; the margin is b_crit / required_depth.

    Examples
    --------
    A single mode of stiffness k and damping zeta has min Re G = -1/(4 k zeta (1 + zeta)), so
    Tlusty's b_crit = 2 k zeta (1 + zeta) / (Kt mu):

    >>> k, zeta, target = 1e7, 0.02, ChatterTarget(kt=6e8, mu=0.5)
    >>> b = target.b_crit(target.mu * -1.0 / (4 * k * zeta * (1 + zeta)))
    >>> round(b / (2 * k * zeta * (1 + zeta) / (6e8 * 0.5)), 12)
    1.0
    """

    kt: float
    mu: float
    required_depth: float | None = None

    def __post_init__(self) -> None:
        if not (self.kt > 0 and math.isfinite(self.kt)):
            raise ValueError(f"ChatterTarget.kt must be finite and > 0 N/m^2, got {self.kt!r}")
        if not (math.isfinite(self.mu) and self.mu != 0):
            raise ValueError(f"ChatterTarget.mu must be finite and non-zero, got {self.mu!r}")
        if self.required_depth is not None and not self.required_depth > 0:
            raise ValueError("ChatterTarget.required_depth must be > 0 m")

    @classmethod
    def from_setup(cls, setup, direction: str = "x", required_depth: float | None = None):
        """Return the target of a milling set-up with one flexible direction.

        Parameters
        ----------
        setup : servotune.chatter.MillingSetup
            The milling set-up (its Kt and engagement).
        direction : {"x", "y"}
            The flexible direction; mu is its directional factor
            (:func:`servotune.chatter.directional_factor`).
        required_depth : float, optional
            Required axial depth of cut [m].

        Returns
        -------
        ChatterTarget
            ``kt`` of the set-up, ``mu`` of the direction.
        """
        from ..chatter import directional_factor

        return cls(setup.kt, directional_factor(setup, direction), required_depth)

    def b_crit(self, min_real: float) -> float:
        """Return the absolute chatter limit b_crit = -1 / (2 Kt min_w Re(mu G)).

        Parameters
        ----------
        min_real : float
            The most negative real part of the ORIENTED FRF mu G [m/N].

        Returns
        -------
        float
            b_crit [m]; inf when ``min_real >= 0`` (no chatter at any depth).
        """
        return math.inf if min_real >= 0 else -1.0 / (2.0 * self.kt * min_real)

    def margin(self, b_crit: float) -> float | None:
        """Return b_crit over the required depth.

        Parameters
        ----------
        b_crit : float
            Absolute chatter limit [m].

        Returns
        -------
        float or None
            The margin [-] (above 1: the required depth is chatter-free); None without a
            required depth.
        """
        return None if self.required_depth is None else b_crit / self.required_depth


@dataclass(frozen=True)
class Design:
    """Values of the design variables (SI): C [N s/m] (axis total), Kv [1/s], Kp [N m s/rad],
    Ti [s], the tuned current set-point notch (:class:`~servotune.drive.NotchFilter`): its
    frequency [rad/s], relative width and depth (gain at its frequency, in (0, 1]), and the
    tuned set-point low-pass' corner frequency [rad/s]. Variables without a drive (or without
    a tuned filter) may be None.

    Raises
    ------
    ValueError
        A value that is not a positive finite number (Ti may be inf: no integral action), or
        None for C; the message names the field and its unit.

    Examples
    --------
    >>> Design(c=-1.0)
    Traceback (most recent call last):
    ...
    ValueError: Design.c must be finite and > 0 N s/m, got -1.0
    """

    c: float
    kv: float | None = None
    kp: float | None = None
    ti: float | None = None
    notch_frequency: float | None = None
    notch_width: float | None = None
    notch_depth: float | None = None
    lowpass_frequency: float | None = None

    def __post_init__(self) -> None:
        for name in VARIABLES:
            value = getattr(self, name)
            if value is None and name != "c":
                continue
            value = positive("Design", name, value, UNITS[name], allow_inf=(name == "ti"))
            object.__setattr__(self, name, value)
        present = [getattr(self, v) is not None for v in NOTCH_VARIABLES]
        if any(present) and not all(present):
            raise ValueError("Design: give the notch's frequency, width and depth together "
                             f"(got {dict(zip(NOTCH_VARIABLES, present, strict=True))})")
        if self.notch_depth is not None and self.notch_depth > 1.0:
            raise ValueError(f"Design.notch_depth must lie in (0, 1] (the notch's gain at its "
                             f"frequency), got {self.notch_depth!r}")

    @property
    def notch(self) -> NotchFilter | None:
        """The tuned current set-point notch (None without one)."""
        if self.notch_frequency is None:
            return None
        return NotchFilter(self.notch_frequency / (2.0 * math.pi), self.notch_width,
                           self.notch_depth)

    def to_dict(self) -> dict:
        """Return the design as JSON-ready data.

        Returns
        -------
        dict
            ``{"c", "kv", "kp", "ti"}`` (SI; None for a variable without a drive) and, with a
            tuned notch, ``notch_frequency`` [rad/s], ``notch_width`` and ``notch_depth``; with
            a tuned low-pass, ``lowpass_frequency`` [rad/s].
        """
        out = {"c": self.c, "kv": self.kv, "kp": self.kp, "ti": self.ti}
        if self.notch_frequency is not None:
            out.update(notch_frequency=self.notch_frequency, notch_width=self.notch_width,
                       notch_depth=self.notch_depth)
        if self.lowpass_frequency is not None:
            out["lowpass_frequency"] = self.lowpass_frequency
        return out


@dataclass(frozen=True)
class TuningProblem:
    """A tuning problem on a structure with viscous guide-way pads and, optionally, a drive.

    Parameters
    ----------
    structure : ModalModel
        The structure (with the pad and force DOFs).
    pads : sequence of str
        Pad DOFs where the guide-way damping C acts (shared equally).
    c : float
        Initial guide-way damping C [N s/m] (axis total).
    drive : Drive, optional
        Initial drive (its Kv, velocity Kp and Ti are the initial gains).
    free : sequence of str
        Which of :data:`VARIABLES` the optimiser may change (``"notch"``: the tuned notch's
        three; ``"lowpass"``: the tuned low-pass' corner).
    bounds : dict, optional
        ``{name: (low, high)}`` in SI; defaults: a factor 100 either way of the initial value;
        for the notch: its frequency within a factor 1.5 either way (and below 0.45 times the
        current controller's sample rate), width 0.05-:data:`NOTCH_WIDTH_MAX`, depth
        0.01-1; for the low-pass: its corner from a factor 8 below its start up to 4 times it
        (and below 0.45 times the current controller's sample rate).
    requirements : Requirements
        Robustness and performance requirements.
    chatter : ChatterTarget, optional
        The chatter-limit objective (needed by a chatter weight > 0).
    weights : (float, float)
        Weights of (compliance peak / initial peak, initial b_crit / b_crit) in the objective.
    tracking_weight : float
        Weight of Kv0/Kv in the objective when Kv is free: the compliance barely depends on
        Kv, so without it Kv would be left anywhere the constraints allow; with it Kv goes as
        high as the position-loop Ms allows (tracking accuracy grows with Kv).
    regimes : tuple of RegimeModel
        The linear guide-way models the design must hold in (default: the viscous pads of the
        paper's sec 4.1). The compliance objective is the worst over the models; every
        constraint holds in every model.
    thrust : ThrustBudget, optional
        The drive's thrust budget (a constraint on C).
    mean_weight : float
        Weight of the mean compliance peak over the models beside the worst (so that the
        regimes that do not bind still improve).
    c_cost_weight : float
        With a thrust budget, the weight of the added damping (C above its lower bound, over
        the range the budget allows) in the objective: damping costs thrust and hardware, so
        it is added only where it buys compliance (the objective is flat in C where it does
        not, and C would otherwise be left anywhere).
    force : str
        Work-piece DOF where the cutting force acts and the compliance is taken.
    n_grid : int
        Initial number of grid frequencies (the exchange refinement adds more).
    held : tuple of int
        Cutting models (indices into ``regimes``) the free variables cannot move: they are
        held at ``held_caps`` [m/N] instead of entering the worst peak (the lexicographic
        objective of :func:`servotune.tuning.solve.tune`).
    held_caps : tuple of float
        Their caps [m/N], one per held model.
    notch : NotchFilter, optional
        The tuned current set-point notch (its initial values): it follows the drive's own
        set-point filters (:meth:`drive_for`); its variables are free when ``free`` names
        them, else it stays as given.
    lowpass : LowPassFilter, optional
        The tuned current set-point low-pass (its start): it replaces the drive's own low-pass
        (give the drive without one); its corner is free when ``free`` names it. A design
        without ``lowpass_frequency`` has no low-pass.

    Raises
    ------
    ValueError
        If the regime models are empty or not RegimeModel, friction models or a free C have
        no pads, a weight is negative or not finite (or both objective weights are zero), a
        variable is unknown or needs a missing drive, nothing is free, a chatter weight has
        no ChatterTarget, the initial C is negative (or not > 0 when free), or the bounds of
        a free variable do not hold its initial value (``0 < low <= initial <= high``).
    servotune.structure.model.UnknownDofError
        If a pad or the force DOF is not a DOF of the structure.
    """

    structure: ModalModel
    pads: tuple[str, ...]
    c: float
    drive: Drive | None = None
    free: tuple[str, ...] = ("c",)
    bounds: dict = field(default_factory=dict)
    requirements: Requirements = field(default_factory=Requirements)
    chatter: ChatterTarget | None = None
    weights: tuple[float, float] = (1.0, 0.0)
    tracking_weight: float = 0.05
    regimes: tuple = (RegimeModel("viscous", "viscous"),)
    thrust: ThrustBudget | None = None
    mean_weight: float = 0.1
    c_cost_weight: float = 0.02
    force: str = "wp.x"
    n_grid: int = 60
    held: tuple[int, ...] = ()
    held_caps: tuple[float, ...] = ()
    notch: NotchFilter | None = None
    lowpass: LowPassFilter | None = None

    def __post_init__(self) -> None:
        regimes = tuple(self.regimes)
        if not regimes or not all(isinstance(m, RegimeModel) for m in regimes):
            raise ValueError("regimes must be a non-empty sequence of RegimeModel")
        if not tuple(self.pads) and any(m.kind != "viscous" for m in regimes):
            raise ValueError("friction regime models need the pad DOFs (pads=...)")
        object.__setattr__(self, "regimes", regimes)
        if self.thrust is not None and not isinstance(self.thrust, ThrustBudget):
            raise ValueError("thrust must be a ThrustBudget or None")
        for name in ("mean_weight", "c_cost_weight"):
            value = getattr(self, name)
            if not (value >= 0 and math.isfinite(value)):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
        pads = tuple(self.pads)
        self.structure.index([*list(pads), self.force])
        object.__setattr__(self, "pads", pads)
        free = expand_free(self.free)
        unknown = [v for v in free if v not in VARIABLES]
        if unknown:
            raise ValueError(f"unknown design variables {unknown}; choose from {VARIABLES}")
        if self.drive is None and (set(free) - {"c"} or self.notch is not None
                                   or self.lowpass is not None):
            raise ValueError(f"free variables {sorted(set(free) - {'c'})} and tuned filters "
                             "need a drive")
        if self.notch is not None and not isinstance(self.notch, NotchFilter):
            raise ValueError("notch must be a NotchFilter or None")
        if self.lowpass is not None and not isinstance(self.lowpass, LowPassFilter):
            raise ValueError("lowpass must be a LowPassFilter or None")
        if self.lowpass is not None and self.drive is not None and self.drive.lowpass is not None:
            raise ValueError("the tuned low-pass replaces the drive's own: give the drive "
                             "without its low-pass (the tuned one's start)")
        if set(free) & set(LOWPASS_VARIABLES) and self.lowpass is None:
            raise ValueError("the low-pass' corner is free but there is no low-pass to tune "
                             "(give TuningProblem.lowpass, its initial values)")
        if set(free) & set(NOTCH_VARIABLES) and self.notch is None:
            raise ValueError("the notch's variables are free but there is no notch to tune "
                             "(give TuningProblem.notch, its initial values)")
        if "c" in free and not pads:
            raise ValueError("tuning C needs the pad DOFs (pads=...)")
        if not free:
            raise ValueError("no free design variables")
        object.__setattr__(self, "free", free)
        if not (self.c >= 0 and math.isfinite(self.c)):
            raise ValueError(f"the initial damping c must be finite and >= 0, got {self.c!r}")
        if "c" in free and self.c <= 0:
            raise ValueError("a free damping C needs a positive initial value")
        w_peak, w_chatter = (float(w) for w in self.weights)
        if w_peak < 0 or w_chatter < 0 or w_peak + w_chatter == 0:
            raise ValueError("weights must be >= 0 and not both zero")
        if not (self.tracking_weight >= 0 and math.isfinite(self.tracking_weight)):
            raise ValueError("tracking_weight must be finite and >= 0")
        if w_chatter > 0 and self.chatter is None:
            raise ValueError("a chatter weight needs a ChatterTarget (chatter=...)")
        design = self.initial_design()
        checked = {}
        defaults = self._filter_bounds(design)
        for name in VARIABLES:
            value = getattr(design, name)
            if value is None and name in NOTCH_VARIABLES + LOWPASS_VARIABLES:
                continue
            lo, hi = self.bounds.get(name, defaults.get(name) or (
                (value / 100.0, value * 100.0) if value else (0, 0)))
            if name in free and not (0 < lo <= value <= hi < math.inf):
                raise ValueError(f"bounds of {name} must satisfy 0 < low <= initial <= high, got "
                                 f"({lo!r}, {hi!r}) with initial {value!r}")
            checked[name] = (float(lo), float(hi))
        object.__setattr__(self, "bounds", checked)

    def _filter_bounds(self, design: Design) -> dict:
        """The default bounds of the tuned filters' variables (see the class docstring)."""
        sampling = self.drive.sampling if self.drive is not None else None
        nyquist = math.inf
        if sampling is not None and not sampling.is_continuous:
            nyquist = 0.45 * 2.0 * math.pi / sampling.current_period
        out = {}
        if design.notch_frequency is not None:
            w0 = design.notch_frequency
            top = min(1.5 * w0, nyquist)
            out.update({"notch_frequency": (min(w0 / 1.5, top), max(top, w0)),
                        "notch_width": (min(0.05, design.notch_width),
                                        max(NOTCH_WIDTH_MAX, design.notch_width)),
                        "notch_depth": (min(0.01, design.notch_depth), 1.0)})
        if design.lowpass_frequency is not None:
            w0 = design.lowpass_frequency
            top = min(4.0 * w0, nyquist)
            out["lowpass_frequency"] = (min(w0 / 8.0, top), max(top, w0))
        return out

    @property
    def cutting_models(self) -> tuple[int, ...]:
        """Indices of the models whose compliance is judged (the cutting regimes)."""
        return tuple(i for i, m in enumerate(self.regimes) if m.cutting)

    @property
    def moving_models(self) -> tuple[int, ...]:
        """Indices of the models in which the axis moves (sliding or viscous pads): there the
        loop hierarchy and the integral time are judged (with the pads stuck the slide does
        not follow the motor and loop bandwidths mean nothing)."""
        return tuple(i for i, m in enumerate(self.regimes) if m.kind in ("sliding", "viscous"))

    @property
    def c_cost(self) -> tuple[float, float] | None:
        """(C_low, span) of the cost of added damping, or None when C costs nothing (no thrust
        budget, or C not free)."""
        if self.thrust is None or "c" not in self.free or not self.c_cost_weight:
            return None
        lo, hi = self.bounds["c"]
        top = min(hi, self.thrust.c_max())
        return lo, max(top - lo, 0.01 * lo)

    def initial_design(self) -> Design:
        """Return the initial design: C and, with a drive, its Kv, velocity Kp and Ti.

        Returns
        -------
        Design
            The design the tuning starts from (the "before" design).
        """
        d = self.drive
        if d is None:
            return Design(c=float(self.c))
        n = self.notch
        filters = {} if n is None else {"notch_frequency": 2.0 * math.pi * n.f_hz,
                                        "notch_width": n.width, "notch_depth": n.depth}
        if self.lowpass is not None:
            filters["lowpass_frequency"] = 2.0 * math.pi * self.lowpass.f_hz
        return Design(c=float(self.c), kv=d.kv, kp=d.velocity_loop.kp, ti=d.velocity_loop.ti,
                      **filters)

    def drive_for(self, design: Design) -> Drive | None:
        """Return the drive with a design's gains.

        Parameters
        ----------
        design : Design
            The design (its Kv, Kp and Ti; set them all when the problem has a drive).

        Returns
        -------
        Drive or None
            The problem's drive with Kv and the velocity PI of the design and, when the
            problem tunes a notch, the design's notch after the drive's own; when it tunes a
            low-pass, the design's (none when the design has no ``lowpass_frequency``); None
            without a drive.
        """
        if self.drive is None:
            return None
        notches = self.drive.notches
        if self.notch is not None and design.notch is not None:
            notches = (*notches, design.notch)
        lowpass = self.drive.lowpass
        if self.lowpass is not None:
            lowpass = self.lowpass_for(design)
        return replace(self.drive, kv=design.kv, notches=notches, lowpass=lowpass,
                       velocity_loop=PIController(kp=design.kp, ti=design.ti))

    def lowpass_for(self, design: Design) -> LowPassFilter | None:
        """Return the tuned low-pass of a design (its corner, the problem's damping ratio), or
        None (no tuned low-pass, or a design without ``lowpass_frequency``).

        Parameters
        ----------
        design : Design
            The design.

        Returns
        -------
        LowPassFilter or None
        """
        if self.lowpass is None or design.lowpass_frequency is None:
            return None
        return LowPassFilter(design.lowpass_frequency / (2.0 * math.pi),
                             self.lowpass.damping_ratio)


# --------------------------------------------------------------------------------------------
# complex arithmetic on (re, im) pairs of numpy arrays or casadi expressions
