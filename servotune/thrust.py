"""The thrust budget of a feed axis and the hardware that could realise a guide-way damping C.

A viscous guide-way damping C damps the structure, but in the feed direction it also resists
feeding: its force C v comes out of the motor's thrust. The budget compares what the axis needs
with what the drive gives, at the slide (SI)::

    accelerating to rapid (peak):        g(v_r) + C v_r + m a    <= (1 - margin) F_peak(v_r)
    rapid traverse (continuous):         g(v_r) + C v_r          <= (1 - margin) F_cont(v_r)
    feeding at each v_f (continuous):    g(v_f) + C v_f + F_cut  <= (1 - margin) F_cont(v_f)

(and, without feed speeds, standing against the cutting force: F_cut <= (1 - margin) F_cont(0)),
with g(v) the Coulomb-Stribeck friction of the guide ways (LuGre steady state without its
viscous part), C the total viscous damping (the identified sigma2 or the design's C that
replaces it), m the moving mass referred to the slide (slide, work piece, screw and motor
inertia through the transmission), a the acceleration of rapid moves, v_r the rapid speed, F_cut
the mean cutting force against the feed, and F_peak(v) = T_peak(v / r) / r, F_cont(v) = T_cont(v
/ r) / r the thrusts of the motor's torque-speed curve at the case's speed
(:class:`servotune.drive.DriveLimits`: a data-sheet table, or the rated torques, flat up to the
top speed or falling at constant power above a rated speed). The acceleration is checked where
it ends, at v_r, where C v_r is largest (and a falling curve lowest); the start of a move, where
the static friction F_s instead of g(v_r) can need more at a small C, is not checked. The
traverse at constant rapid speed is a continuous load, however long the move. All axis friction
is lumped at the guide ways (the paper's sec 3), so the transmission's efficiency is already in
the friction and is taken as 1.

Each case is affine in C, ``F_fix + C v <= F_usable``, so the largest C the budget allows is
``min over the cases with v > 0 of (F_usable - F_fix) / v`` (:meth:`ThrustBudget.c_max`).

What could realise C (:func:`c_realisations`):

* a **viscous element** (hydrostatic guides, a viscous damper in the feed direction): the added
  damping dC = C - sigma2 costs dC v of force and dC v^2 of power at every speed;
* a **friction damper** (a preloaded pad with its own contact stiffness k, a Jenkins element):
  its describing function at the pad vibration amplitude A the process force gives,
  Ceq = 4 F_d (A - F_d/k) / (pi w A^2) (the paper's Eq 9 with the area of its own Fig 6 cycle,
  see :mod:`servotune.friction.equivalent`), equals dC for the friction level
  ``F_d = (k A / 2) (1 - sqrt(1 - pi w dC / k))``, which exists while dC <= k / (pi w). It costs
  F_d of thrust at every speed but damps only while the pads vibrate beyond F_d/k and reverse:
  not while feeding, when the friction force does not change sign.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 3, 4.2 (Eq 8-10). Y. Altintas, Manufacturing Automation, 2nd ed. (2012), sec 6.2 (feed
drive sizing: friction, inertia and cutting loads). C. Brecher, M. Weck, Werkzeugmaschinen 3:
Mechatronische Systeme, Vorschubantriebe, Prozessdiagnose, 2nd ed., Springer (2021), ch 4
(sizing feed drives; hydrostatic guides).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.optimize

from .drive import Drive, DriveLimits
from .friction.equivalent import describing_function
from .friction.law import FrictionLaw
from .friction.laws.lugre import LuGreFriction
from .friction.lugre import LuGreParameters
from .regimes import Operation
from .structure.model import ModalModel

__all__ = ["ThrustCase", "ThrustBudget", "CRealisation", "moving_mass", "holding_forces",
           "thrust_budget", "c_realisations"]


def moving_mass(structure: ModalModel, pads, drive: Drive | None = None) -> float:
    """The mass the motor accelerates, referred to the slide [kg].

    The rigid-body motion of the structure with the pads free (the axis travel) is found as the
    null space of K, scaled to a unit mean pad displacement; its kinetic-energy mass
    ``phi^T M phi`` holds the slide, the work piece and the rotating parts through the
    transmission (a motor inertia J counts J/r^2).

    Parameters
    ----------
    structure : ModalModel
        The structure with its pads free (not grounded).
    pads : sequence of str
        The pad DOFs (relative X at each guide-way pad).
    drive : Drive, optional
        Not used: the rotating parts enter through the structure's mass matrix.

    Returns
    -------
    float
        The moving mass [kg].

    Raises
    ------
    ValueError
        When the structure has no rigid-body travel along the pads.
    UnknownDofError
        When a pad is not a DOF of the structure.

    Examples
    --------
    Two masses on a spring, pads on the first:

    >>> s = ModalModel([[100.0, 0.0], [0.0, 50.0]], [[1e6, -1e6], [-1e6, 1e6]], ["pad1.x", "wp.x"])
    >>> round(moving_mass(s, ["pad1.x"]), 6)
    150.0
    """
    k, m = structure.stiffness, structure.mass
    lam, vec = scipy.linalg.eigh(k, m)
    scale = max(abs(lam).max(), 1e-300)
    rigid = vec[:, np.abs(lam) <= 1e-9 * scale]
    idx = structure.index(list(pads))
    if rigid.shape[1] == 0:
        held = holding_forces(structure, pads)
        where = ", ".join(f"{d} {f:.3g} N" for d, f in held[:4])
        raise ValueError(
            "the structure has no rigid-body travel (it is grounded): moving the pads together "
            f"by 1 m takes at least {math.hypot(*(f for _, f in held)) if held else 0.0:.3g} N "
            f"of holding forces ({where}{' ...' if len(held) > 4 else ''}), so the moving mass "
            "of the axis cannot be found and a drive cannot move it; if these are the FE "
            "model's guide-way springs, name them in axis.toml, [structure] guideway_springs = "
            "{\"<DOF>\" = <N/m>} (the friction model at the pads takes their place); else leave "
            "the pads free in the model")
    rows = rigid[idx]  # pad displacements of each rigid mode
    coeff, *_ = np.linalg.lstsq(rows, np.ones(len(idx)), rcond=None)
    phi = rigid @ coeff
    if np.abs(rows @ coeff - 1.0).max() > 1e-6:
        raise ValueError("no rigid-body motion moves all pads together; check the pad DOFs")
    return float(phi @ m @ phi)


def holding_forces(structure: ModalModel, pads) -> list[tuple[str, float]]:
    """Return the forces that hold a structure when its pads move together by 1 m and every
    other DOF is left in equilibrium, by DOF, largest first.

    ``r`` with ``r[pads] = 1`` and ``K_ff r_f = -K_fp 1`` at the other DOFs (least squares
    where the structure is free there); ``f = K r`` is then the stiffness with which the
    structure holds its pads against a common travel: 0 for a slide free along its guide ways,
    the guide-way springs' stiffness to the ground for an FE export that keeps them.

    Parameters
    ----------
    structure : ModalModel
        The structure.
    pads : sequence of str
        The pad DOFs.

    Returns
    -------
    list of (str, float)
        (DOF, force [N]) for the forces above 1e-6 of the largest, largest first.

    Examples
    --------
    A slide held by a 1e7 N/m spring to the ground at its pad:

    >>> s = ModalModel([[100.0, 0.0], [0.0, 50.0]], [[1.1e7, -1e6], [-1e6, 1e6]],
    ...                ["pad1.x", "wp.x"])
    >>> [(d, round(f)) for d, f in holding_forces(s, ["pad1.x"])]
    [('pad1.x', 10000000)]
    """
    k = np.asarray(structure.stiffness, dtype=float)
    idx = structure.index(list(pads))
    free = np.setdiff1d(np.arange(k.shape[0]), idx)
    r = np.zeros(k.shape[0])
    r[idx] = 1.0
    if free.size:
        sol, *_ = np.linalg.lstsq(k[np.ix_(free, free)], -k[np.ix_(free, idx)].sum(axis=1),
                                  rcond=None)
        r[free] = sol
    f = k @ r
    top = float(np.abs(f).max()) if f.size else 0.0
    order = np.argsort(-np.abs(f))
    return [(structure.dofs[i], float(f[i])) for i in order if abs(f[i]) > 1e-6 * top > 0]


@dataclass(frozen=True)
class ThrustCase:
    """One load case of the budget (SI)."""

    name: str
    speed: float
    thrust_kind: str          # "peak" or "continuous"
    available: float          # [N]
    usable: float             # (1 - margin) x available [N]
    terms: tuple              # ((name, force [N]), ...)

    @property
    def needed(self) -> float:
        """Sum of the terms: the thrust the case needs [N]."""
        return float(sum(f for _, f in self.terms))

    @property
    def fits(self) -> bool:
        """Needed within usable, to the optimiser's constraint tolerance (1e-6 relative)."""
        return self.needed <= self.usable * (1 + 1e-6)

    @property
    def utilisation(self) -> float:
        """Needed over available thrust [-]."""
        return self.needed / self.available

    def to_dict(self) -> dict:
        """Return the case as a JSON-ready dictionary (forces in N, speed in m/s).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return {"name": self.name, "speed_m_per_s": self.speed, "thrust": self.thrust_kind,
                "available_n": self.available, "usable_n": self.usable,
                "needed_n": self.needed, "fits": self.fits,
                "utilisation": self.utilisation,
                "terms_n": {name: force for name, force in self.terms}}


@dataclass(frozen=True)
class ThrustBudget:
    """What the axis needs against what the drive gives (see the module docstring).

    Attributes
    ----------
    thrust_peak, thrust_continuous : float
        [N] at the slide: the rated (largest) thrusts; they hold at every speed when ``limits``
        is None.
    margin : float
        Fraction kept in reserve.
    mass : float
        Moving mass referred to the slide [kg].
    friction : FrictionLaw or LuGreParameters
        Axis-total friction law (its viscous part is replaced by the C of each evaluation; its
        steady sliding friction without it,
        :meth:`~servotune.friction.law.FrictionLaw.steady_force`, is g(v)). LuGre parameters
        are taken as their law.
    operation : Operation
    limits : DriveLimits, optional
        The motor's torques over speed (:meth:`DriveLimits.peak`, :meth:`DriveLimits.continuous`)
        with ``ratio``: the thrust of a case is taken at its speed. Its largest torques over
        ``ratio`` must be ``thrust_peak`` and ``thrust_continuous``.
    ratio : float, optional
        Transmission ratio r [m/rad] (with ``limits``).

    Raises
    ------
    ValueError
        ``limits`` without ``ratio`` or the other way round, thrusts that are not the limits'
        torques over r, or a speed of the operation the motor cannot reach (beyond its top speed
        or its torque-speed curve).

    Examples
    --------
    A traverse at 0.5 m/s against 300 N of Coulomb friction with 12 kN of continuous thrust,
    20 % kept: C <= (0.8 x 12000 - 300) / 0.5 = 18600 N s/m; accelerating 1000 kg at 2 m/s^2
    with 40 kN of peak thrust allows more, (0.8 x 40000 - 300 - 2000) / 0.5 = 59400 N s/m.

    >>> p = LuGreParameters(fc=300.0, fs=300.0, vs=0.01, delta=1.0, sigma0=1e9, sigma1=0.0,
    ...                     sigma2=0.0)
    >>> b = ThrustBudget(4e4, 1.2e4, 0.2, 1000.0, p,
    ...                  Operation(feed_speeds=(), rapid_speed=0.5, acceleration=2.0))
    >>> round(b.c_max()), b.c_max_case()
    (18600, 'rapid traverse')
    """

    thrust_peak: float
    thrust_continuous: float
    margin: float
    mass: float
    friction: FrictionLaw
    operation: Operation
    limits: DriveLimits | None = None
    ratio: float | None = None

    def __post_init__(self) -> None:
        law = LuGreFriction(self.friction) if isinstance(self.friction, LuGreParameters) \
            else self.friction
        if not isinstance(law, FrictionLaw):
            raise ValueError(f"ThrustBudget.friction must be a FrictionLaw or LuGreParameters, "
                             f"got {self.friction!r}")
        object.__setattr__(self, "friction", law)
        # the law without its viscous part: g(v) (the viscous part is C v of each case)
        object.__setattr__(self, "_dry", law.with_viscous(0.0))
        if (self.limits is None) != (self.ratio is None):
            raise ValueError("ThrustBudget: give limits and ratio together (the torque-speed "
                             "curve at the motor and the transmission to the slide), or neither")
        if self.limits is None:
            return
        if not isinstance(self.limits, DriveLimits):
            raise ValueError("ThrustBudget.limits must be a DriveLimits or None")
        if not (math.isfinite(self.ratio) and self.ratio > 0):
            raise ValueError(f"ThrustBudget.ratio must be finite and > 0 [m/rad], got "
                             f"{self.ratio!r}")
        for name, torque in (("thrust_peak", self.limits.torque_peak),
                             ("thrust_continuous", self.limits.torque_continuous)):
            if not math.isclose(getattr(self, name), torque / self.ratio, rel_tol=1e-9):
                raise ValueError(f"ThrustBudget.{name} ({getattr(self, name):.6g} N) is not the "
                                 f"limits' torque over the ratio ({torque / self.ratio:.6g} N)")
        op = self.operation
        for v in (*((op.rapid_speed,) if op.rapid_speed is not None else ()), *op.feed_speeds):
            try:
                self.thrust_peak_at(v)
            except ValueError as exc:
                raise ValueError(f"ThrustBudget: the operation's speed of {v:.6g} m/s at the "
                                 f"slide: {exc}") from None

    def thrust_peak_at(self, v: float) -> float:
        """Return the peak thrust [N] at a slide speed [m/s]: T_peak(v / r) / r.

        Parameters
        ----------
        v : float
            Slide speed [m/s], >= 0.

        Returns
        -------
        float
            The peak thrust [N].

        Raises
        ------
        ValueError
            Beyond the motor's top speed or its torque-speed curve.
        """
        if self.limits is None:
            return self.thrust_peak
        return self.limits.peak(v / self.ratio) / self.ratio

    def thrust_continuous_at(self, v: float) -> float:
        """Return the continuous thrust [N] at a slide speed [m/s]: T_cont(v / r) / r.

        Parameters
        ----------
        v : float
            Slide speed [m/s], >= 0.

        Returns
        -------
        float
            The continuous thrust [N].

        Raises
        ------
        ValueError
            Beyond the motor's top speed or its torque-speed curve.
        """
        if self.limits is None:
            return self.thrust_continuous
        return self.limits.continuous(v / self.ratio) / self.ratio

    def _coulomb(self, v: float) -> float:
        return abs(float(self._dry.steady_force(v))) if v else 0.0

    def _case(self, name, v, kind, terms, extra_friction) -> ThrustCase:
        if extra_friction:
            terms = [*terms, ("friction damper", extra_friction)]
        available = (self.thrust_peak_at(v) if kind == "peak" else
                     self.thrust_continuous_at(v))
        return ThrustCase(name, v, kind, available, (1 - self.margin) * available, tuple(terms))

    def cases(self, c: float, extra_friction: float = 0.0) -> tuple[ThrustCase, ...]:
        """Return the load cases with a total viscous damping and an added friction level.

        At the rapid speed, one peak-thrust case at the end of the acceleration (friction,
        viscous force and acceleration) and one continuous case traversing at constant speed
        (friction and viscous force); one continuous case per feed speed (friction, viscous
        force and the feed force); and a standing case against the feed force when there is no
        feed speed. Each against the usable thrust at its own speed.

        Parameters
        ----------
        c : float
            Total viscous damping C [N s/m].
        extra_friction : float, optional
            Friction level of a friction damper [N], added to every moving case (default 0).

        Returns
        -------
        tuple of ThrustCase
            The cases: accelerating to rapid, rapid traverse, feeding, standing.
        """
        op, out = self.operation, []
        if op.rapid_speed is not None:
            v = op.rapid_speed
            moving = [("friction g(v)", self._coulomb(v)), ("viscous C v", c * v)]
            out.append(self._case("accelerating to rapid", v, "peak",
                                  [*moving, ("acceleration m a", self.mass * op.acceleration)],
                                  extra_friction))
            out.append(self._case("rapid traverse", v, "continuous", moving, extra_friction))
        for v in op.feed_speeds:
            out.append(self._case(f"feeding {v * 1e3:.3g} mm/s", v, "continuous",
                                  [("friction g(v)", self._coulomb(v)), ("viscous C v", c * v),
                                   ("cutting force", op.feed_force)], extra_friction))
        if not op.feed_speeds:  # holding against the cutting force at rest
            out.append(self._case("standing", 0.0, "continuous",
                                  [("cutting force", op.feed_force)], 0.0))
        return tuple(out)

    def linear_form(self) -> tuple[tuple[float, float, float, str], ...]:
        """Return each case as ``fixed + c * speed <= usable``, the form the tuning constrains.

        Returns
        -------
        tuple of (float, float, float, str)
            (fixed [N], speed [m/s], usable [N] at that speed, name) per case, in the order of
            :meth:`cases`.
        """
        out = []
        for case in self.cases(0.0):
            out.append((case.needed, case.speed, case.usable, case.name))
        return tuple(out)

    def c_limits(self) -> dict[str, float]:
        """Return the largest total viscous damping [N s/m] each case with a speed allows.

        Returns
        -------
        dict
            ``(usable - fixed) / speed`` by case name (negative when even C = 0 does not fit).
        """
        return {name: (usable - fixed) / speed for fixed, speed, usable, name
                in self.linear_form() if speed > 0}

    def c_max(self) -> float:
        """Return the largest total viscous damping [N s/m] every case allows.

        The minimum over the cases of :meth:`c_limits`; ``inf`` when no case has a speed;
        negative when even C = 0 does not fit.

        Returns
        -------
        float
            C_max [N s/m].
        """
        limits = self.c_limits()
        return min(limits.values()) if limits else math.inf

    def c_max_case(self) -> str | None:
        """Return the name of the case that sets :meth:`c_max` (None when no case has a speed).

        Returns
        -------
        str or None
            The binding case.
        """
        limits = self.c_limits()
        return min(limits, key=limits.get) if limits else None

    def to_dict(self, c: float) -> dict:
        """Return the budget at a damping as a JSON-ready dictionary.

        Parameters
        ----------
        c : float
            Total viscous damping C [N s/m] the cases are evaluated at.

        Returns
        -------
        dict
            Thrusts [N] (rated), margin, moving mass [kg], ``c_max`` [N s/m] and the case that
            sets it, the limit of each case (``c_max_by_case``), whether all cases fit, and the
            cases (:meth:`ThrustCase.to_dict`).
        """
        cases = self.cases(c)
        return {"thrust_peak_n": self.thrust_peak, "thrust_continuous_n": self.thrust_continuous,
                "margin": self.margin, "moving_mass_kg": self.mass,
                "c_max": self.c_max(), "c_max_case": self.c_max_case(),
                "c_max_by_case": self.c_limits(), "fits": all(x.fits for x in cases),
                "cases": [x.to_dict() for x in cases]}


def thrust_budget(drive: Drive | None, friction: FrictionLaw | LuGreParameters | None,
                  operation: Operation | None, structure: ModalModel, pads,
                  margin: float) -> ThrustBudget | None:
    """Return the thrust budget of an axis, or None when it cannot be drawn up.

    Parameters
    ----------
    drive : Drive or None
        The drive; its torque limits (and their torque-speed curve) through the transmission
        give the thrusts at each case's speed.
    friction : FrictionLaw, LuGreParameters or None
        Axis-total guide-way friction law.
    operation : Operation or None
        The regimes (feed speeds, rapid speed, acceleration, feed force).
    structure : ModalModel
        The structure, for the moving mass (:func:`moving_mass`).
    pads : sequence of str
        The pad DOFs.
    margin : float
        Fraction of the thrust kept in reserve [-].

    Returns
    -------
    ThrustBudget or None
        None when the drive, its torque limits, the friction or the operation is missing.

    Raises
    ------
    ValueError
        When the structure has no rigid-body travel along the pads (:func:`moving_mass`), or
        a speed of the operation is beyond the motor's top speed or torque-speed curve.
    """
    if drive is None or drive.limits is None or friction is None or operation is None:
        return None
    return ThrustBudget(drive.thrust_peak, drive.thrust_continuous, float(margin),
                        moving_mass(structure, pads, drive), friction, operation,
                        limits=drive.limits, ratio=drive.ratio)


@dataclass(frozen=True)
class CRealisation:
    """One way to build a guide-way damping (SI)."""

    option: str
    added_damping: float                 # dC = C - sigma2 [N s/m]
    force_feed: float | None             # extra force while feeding (highest feed) [N]
    power_feed: float | None             # [W]
    force_rapid: float | None            # extra force at rapid traverse [N]
    power_rapid: float | None            # [W]
    friction_level: float | None         # friction damper: F_d [N]
    fits: bool                           # realises C wherever the design relies on it, in budget
    note: str
    damps_while_feeding: bool = True     # a friction damper does not (its force keeps its sign)
    fits_thrust: bool | None = None      # the thrust budget alone (None: no torque limits)

    def to_dict(self) -> dict:
        """Return the option as a JSON-ready dictionary of its fields (SI).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        return dataclasses.asdict(self)


def _friction_damper_level(dc: float, amplitude: float, omega: float,
                           stiffness: float) -> float | None:
    """F_d with Ceq(F_d) = dc for the elasto-plastic element (closed form), or None."""
    x = math.pi * omega * dc / stiffness
    if x > 1.0:
        return None
    return 0.5 * stiffness * amplitude * (1.0 - math.sqrt(1.0 - x))


def c_realisations(budget: ThrustBudget | None, c: float, sigma2: float,
                   amplitude: float | None, frequency: float | None,
                   contact_stiffness: float | None,
                   operation: Operation | None = None) -> tuple[CRealisation, ...]:
    """Return the options that would realise a total viscous damping over the guide ways' own.

    Each option realises ``c`` over the identified ``sigma2`` [N s/m], with its cost and
    whether it fits.

    An option fits when the thrust budget holds with it AND it gives the damping in every
    regime the design was tuned for: a friction damper damps only while the pads vibrate and
    reverse, so it cannot realise C for an axis that also works feeding (the design's feeding
    claims rely on C), and its equivalent damping holds at the process amplitude only
    (falling about as 1/A above it; the note gives Ceq at a quarter and at three times the
    amplitude).

    Parameters
    ----------
    budget : ThrustBudget, optional
        Without it the options are reported without a verdict on the thrust.
    c : float
        The total viscous damping C the design needs [N s/m].
    sigma2 : float
        The viscous damping the guide ways have [N s/m].
    amplitude, frequency : float, optional
        Pad vibration amplitude [m] and angular frequency [rad/s] at the process force (for the
        friction damper).
    contact_stiffness : float, optional
        Tangential stiffness of the friction damper's contact [N/m] (the guide ways' sigma0).
    operation : Operation, optional
        The regimes of the axis (default: the budget's).

    Returns
    -------
    tuple of CRealisation
        "none" alone when ``c <= sigma2``; else a viscous element, and a friction damper when
        ``amplitude``, ``frequency`` and ``contact_stiffness`` are given.
    """
    dc = float(c) - float(sigma2)
    op = operation if operation is not None else (
        budget.operation if budget is not None else None)
    feeding = bool(op is not None and op.feed_speeds)
    v_feed = max(op.feed_speeds) if op is not None and op.feed_speeds else None
    v_rapid = op.rapid_speed if op is not None else None
    out = []
    if dc <= 0:
        fits = budget is None or all(x.fits for x in budget.cases(c))
        out.append(CRealisation(
            "none", dc, 0.0, 0.0, 0.0, 0.0, None, fits,
            "the design needs no more viscous damping than the guide ways have"
            + ("" if dc == 0 else f" (it assumes {abs(dc):.3g} N s/m less: lower-friction "
                                  "guide ways or lubricant)")))
        return tuple(out)
    fits_viscous = None if budget is None else all(x.fits for x in budget.cases(c))
    out.append(CRealisation(
        "viscous element", dc,
        None if v_feed is None else dc * v_feed, None if v_feed is None else dc * v_feed ** 2,
        None if v_rapid is None else dc * v_rapid,
        None if v_rapid is None else dc * v_rapid ** 2, None, bool(fits_viscous is not False),
        "hydrostatic guides or a viscous damper in the feed direction: damps in every regime, "
        "resists feeding with dC v" + ("" if budget is not None else
                                       " (no torque limits given: the thrust is not checked)"),
        damps_while_feeding=True, fits_thrust=fits_viscous))
    if amplitude is None or frequency is None or not contact_stiffness:
        return tuple(out)
    level = _friction_damper_level(dc, amplitude, frequency, contact_stiffness)
    if level is None:
        out.append(CRealisation(
            "friction damper", dc, None, None, None, None, None, False,
            f"no friction level reaches {dc:.3g} N s/m at the pad amplitude {amplitude:.3g} m "
            f"(the most is k/(pi w) = {contact_stiffness / (math.pi * frequency):.3g} N s/m)",
            damps_while_feeding=False))
        return tuple(out)
    lugre_level = _lugre_damper_level(dc, amplitude, frequency, contact_stiffness, level)
    fits_thrust = None
    if budget is not None:
        fits_thrust = all(x.fits for x in budget.cases(sigma2,
                                                       extra_friction=lugre_level or level))
    at = {k: _jenkins_ceq(level, k * amplitude, frequency, contact_stiffness)
          for k in (0.25, 3.0)}
    why_not = []
    if feeding:
        why_not.append("it does not damp while feeding (its force keeps its sign), where the "
                       "design's feeding claims rely on C: a viscous element is needed there")
    if fits_thrust is False:
        why_not.append("the thrust budget does not hold with its friction")
    out.append(CRealisation(
        "friction damper", dc, level, None if v_feed is None else level * v_feed, level,
        None if v_rapid is None else level * v_rapid, level,
        bool(fits_thrust is not False) and not feeding,
        f"a preloaded friction pad of {level:.4g} N (LuGre describing function: "
        f"{'n/a' if lugre_level is None else f'{lugre_level:.4g}'} N) on a contact of "
        f"{contact_stiffness:.3g} N/m gives Ceq = dC at A = {amplitude:.3g} m and "
        f"{frequency / (2 * math.pi):.1f} Hz, but {at[0.25]:.3g} N s/m at a quarter and "
        f"{at[3.0]:.3g} N s/m at three times that amplitude; it damps only while the pads "
        f"vibrate beyond {level / contact_stiffness:.3g} m and reverse (standing)"
        + (f"; does not fit: {'; '.join(why_not)}" if why_not else ""),
        damps_while_feeding=False, fits_thrust=fits_thrust))
    return tuple(out)


def _jenkins_ceq(level: float, amplitude: float, omega: float, stiffness: float) -> float:
    """Equivalent damping [N s/m] of an elasto-plastic (Jenkins) element of slip force
    ``level`` and stiffness ``stiffness`` at amplitude [m] and angular frequency [rad/s]:
    4 F (A - F/k) / (pi w A^2) once it slips (A > F/k), else 0 (the module docstring)."""
    if amplitude <= level / stiffness:
        return 0.0
    return 4.0 * level * (amplitude - level / stiffness) / (math.pi * omega * amplitude ** 2)


def _lugre_damper_level(dc, amplitude, omega, stiffness, guess) -> float | None:
    """F_d of a LuGre element (fc = fs = F_d, sigma1 = sigma2 = 0, vs = 1 mm/s) whose
    describing function gives dc at (amplitude, omega), near the closed-form ``guess``."""
    def ceq(level):
        p = LuGreParameters(fc=level, fs=level, vs=1e-3, delta=1.0, sigma0=stiffness,
                            sigma1=0.0, sigma2=0.0)
        return float(describing_function(p, amplitude, omega)[0]) - dc

    lo, hi = 1e-3 * guess, 0.5 * stiffness * amplitude
    try:
        if ceq(lo) * ceq(hi) > 0:
            return None
        return float(scipy.optimize.brentq(ceq, lo, min(hi, 4 * guess) if ceq(min(hi, 4 * guess))
                                           * ceq(lo) < 0 else hi, rtol=1e-6))
    except (ValueError, RuntimeError):
        return None
