"""Milling set-up and the directional matrices of the regenerative cutting force.

Geometry and force model (straight-flute end mill, equal tooth pitch)::

        y ^                      tool rotates clockwise (seen from the spindle);
          |   phi_j              tooth j at angle phi_j(t) = Omega t + 2 pi j / N,
          |  /                   measured from the +y axis in the sense of rotation
          | /
     -----o-----> x = feed       h_j = (f_z + dx) sin phi_j + dy cos phi_j   (chip thickness)

A tooth in the cut (``entry_angle < phi_j < exit_angle``) feels the tangential force
``F_t = K_t b h`` and the normal (radial) force ``F_n = K_n b h`` [N], with the axial depth of cut
b [m] and the cutting coefficients K_t, K_n [N/m^2]. Projected on x and y and summed over the
teeth, the part of the force that depends on the vibration q = (x, y) of the tool relative to the
work piece is (Insperger, Mann, Stepan and Bayly 2003, Eq 4-7)::

    F(t) = -b H(t) (q(t) - q(t - T)),      T = 60 / (N n_rpm)   (tooth passing period)

    H_xx = sum_j g_j sin(phi_j) (K_t cos(phi_j) + K_n sin(phi_j))
    H_xy = sum_j g_j cos(phi_j) (K_t cos(phi_j) + K_n sin(phi_j))
    H_yx = sum_j g_j sin(phi_j) (-K_t sin(phi_j) + K_n cos(phi_j))
    H_yy = sum_j g_j cos(phi_j) (-K_t sin(phi_j) + K_n cos(phi_j))

with g_j = 1 while tooth j cuts and 0 otherwise. H(t) [N/m^2] is T-periodic. Its mean over one
period is the *directional matrix* D of the zero-order approximation (Altintas and Budak 1995)::

    D = (1/T) int_0^T H(t) dt = -(N K_t / (4 pi)) [alpha],      K_r = K_n / K_t

    alpha_xx = 1/2 [ cos 2phi - 2 K_r phi + K_r sin 2phi ]   evaluated from entry to exit angle
    alpha_xy = 1/2 [ -sin 2phi - 2 phi + K_r cos 2phi ]
    alpha_yx = 1/2 [ -sin 2phi + 2 phi + K_r cos 2phi ]
    alpha_yy = 1/2 [ -cos 2phi - 2 K_r phi - K_r sin 2phi ]

(Altintas and Budak 1995, Eq 12; Altintas 2012, Eq 3.59). The *directional factor* of one
direction is ``mu_d = D_dd / K_t`` (dimensionless), so that ``K_t mu_d`` is the mean cutting
stiffness per unit depth felt in that direction. In a full slot ``mu_x = mu_y = N K_r / 4``.

Cutting coefficients: this module takes the normal coefficient ``kn`` in N/m^2, as Insperger
and Stepan do (F_n = K_n b h). Altintas and Budak write the radial force as a *ratio*,
F_r = K_r F_t with K_r = K_n / K_t dimensionless; :meth:`MillingSetup.from_ratio` takes that
form and :attr:`MillingSetup.kr_ratio` returns it.

References
----------
Y. Altintas, E. Budak, "Analytical prediction of stability lobes in milling", CIRP Annals 44
(1995) 357-362.
Y. Altintas, Manufacturing Automation, 2nd ed., Cambridge University Press (2012), ch 3.
T. Insperger, B. P. Mann, G. Stepan, P. V. Bayly, "Stability of up-milling and down-milling,
part 1: alternative analytical methods", Int J Machine Tools Manuf 43 (2003) 25-34.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..validation import positive

__all__ = [
    "DIRECTIONS",
    "MillingSetup",
    "directional_factor",
    "directional_matrix",
    "periodic_directional_matrix",
]

MILLING_MODES = ("down", "up")
#: the two directions in the plane of the cut, in the order of the 2 x 2 matrices
DIRECTIONS = ("x", "y")


@dataclass(frozen=True)
class MillingSetup:
    """A milling operation: the tool's teeth, the cutting coefficients and the engagement.

    Parameters
    ----------
    teeth : int
        Number of teeth N (equal pitch), >= 1.
    kt : float
        Tangential cutting coefficient K_t [N/m^2], > 0 (F_t = K_t b h).
    kn : float
        Normal (radial) cutting coefficient K_n [N/m^2], >= 0 (F_n = K_n b h). This is the
        absolute coefficient of Insperger and Stepan, *not* Altintas' ratio K_r = K_n / K_t;
        use :meth:`from_ratio` to give the ratio.
    radial_immersion : float
        Radial depth of cut over tool diameter, a/D, in (0, 1]; 1 is a full slot.
    milling : {"down", "up"}
        Down (climb) milling: the tooth enters the cut at ``arccos(2 a/D - 1)`` and leaves it at
        pi. Up (conventional) milling: it enters at 0 and leaves at ``arccos(1 - 2 a/D)``.
    helix_angle : float
        Helix angle [rad], in [0, pi/2). Recorded but **ignored**: both the zero-order and the
        semi-discretisation models here are for straight flutes. A helix smooths the entry and
        exit of the teeth; it barely changes zero-order lobes but can shift the flip lobes of
        low radial immersion (Insperger et al. 2006), so treat low-immersion results with a
        helical tool as approximate.

    Raises
    ------
    ValueError
        If a value is out of range, naming the field and the accepted range.

    Examples
    --------
    In a full slot one tooth is always engaged on average for N = 2, and the mean directional
    factor in the feed direction is N K_r / 4:

    >>> s = MillingSetup(teeth=2, kt=6e8, kn=2e8, radial_immersion=1.0)
    >>> round(s.kr_ratio, 4), round(directional_factor(s, "x"), 4)
    (0.3333, 0.1667)
    >>> round(math.degrees(s.entry_angle)), round(math.degrees(s.exit_angle))
    (0, 180)
    """

    teeth: int
    kt: float
    kn: float
    radial_immersion: float = 1.0
    milling: str = "down"
    helix_angle: float = 0.0

    def __post_init__(self) -> None:
        teeth = self.teeth
        if isinstance(teeth, bool) or not float(teeth).is_integer() or teeth < 1:
            raise ValueError(f"MillingSetup.teeth must be a whole number >= 1, got {teeth!r}")
        object.__setattr__(self, "teeth", int(teeth))
        object.__setattr__(self, "kt", positive("MillingSetup", "kt", self.kt, "N/m^2",
                                                "give the tangential cutting coefficient K_t"))
        object.__setattr__(self, "kn", positive("MillingSetup", "kn", self.kn, "N/m^2",
                                                "give the normal cutting coefficient K_n",
                                                allow_zero=True))
        ae = positive("MillingSetup", "radial_immersion", self.radial_immersion, "(a/D)",
                      "give a/D in (0, 1]; 1 is a full slot")
        if ae > 1.0:
            raise ValueError(f"MillingSetup.radial_immersion (a/D) must lie in (0, 1], got "
                             f"{ae!r}; 1 is a full slot")
        object.__setattr__(self, "radial_immersion", ae)
        milling = str(self.milling).lower()
        if milling not in MILLING_MODES:
            raise ValueError(f"MillingSetup.milling must be 'down' or 'up', got {self.milling!r}")
        object.__setattr__(self, "milling", milling)
        helix = positive("MillingSetup", "helix_angle", self.helix_angle, "rad",
                         allow_zero=True)
        if helix >= math.pi / 2:
            raise ValueError(f"MillingSetup.helix_angle must be in [0, pi/2) rad, got {helix!r}")
        object.__setattr__(self, "helix_angle", helix)

    @classmethod
    def from_ratio(cls, teeth: int, kt: float, kr: float, radial_immersion: float = 1.0,
                   milling: str = "down", helix_angle: float = 0.0) -> MillingSetup:
        """Build a set-up from Altintas' radial force *ratio* K_r = K_n / K_t (dimensionless).

        Parameters
        ----------
        teeth : int
            Number of teeth N.
        kt : float
            Tangential cutting coefficient K_t [N/m^2].
        kr : float
            Radial force ratio K_r = K_n / K_t [-], >= 0.
        radial_immersion : float, optional
            Radial depth over tool diameter a/D (default 1, a full slot).
        milling : {"down", "up"}, optional
            Milling mode (default "down").
        helix_angle : float, optional
            Helix angle [rad] (default 0).

        Returns
        -------
        MillingSetup
            The set-up with ``kn = kr * kt``.

        Raises
        ------
        ValueError
            When ``kr`` is negative or not finite, or for the reasons of :class:`MillingSetup`.

        Examples
        --------
        >>> MillingSetup.from_ratio(teeth=4, kt=2e9, kr=0.3).kn
        600000000.0
        """
        kr = positive("MillingSetup.from_ratio", "kr", kr, "",
                      "give the dimensionless ratio K_n/K_t", allow_zero=True)
        return cls(teeth=teeth, kt=kt, kn=kr * float(kt), radial_immersion=radial_immersion,
                   milling=milling, helix_angle=helix_angle)

    @property
    def kr_ratio(self) -> float:
        """Altintas' radial force ratio K_r = K_n / K_t [-]."""
        return self.kn / self.kt

    @property
    def entry_angle(self) -> float:
        """Angle [rad] at which a tooth enters the cut (from +y, in the sense of rotation)."""
        if self.milling == "up":
            return 0.0
        return math.acos(2.0 * self.radial_immersion - 1.0)

    @property
    def exit_angle(self) -> float:
        """Angle [rad] at which a tooth leaves the cut."""
        if self.milling == "up":
            return math.acos(1.0 - 2.0 * self.radial_immersion)
        return math.pi

    def to_dict(self) -> dict:
        """JSON-ready dictionary (SI; angles also in degrees under ``*_deg`` keys).

        Returns
        -------
        dict
            JSON-ready values (str, numbers, lists, None).
        """
        return {
            "teeth": self.teeth,
            "kt": self.kt,
            "kn": self.kn,
            "kr_ratio": self.kr_ratio,
            "radial_immersion": self.radial_immersion,
            "milling": self.milling,
            "helix_angle": self.helix_angle,
            "entry_angle_deg": math.degrees(self.entry_angle),
            "exit_angle_deg": math.degrees(self.exit_angle),
        }


def _antiderivative(setup: MillingSetup, phi) -> np.ndarray:
    """int H(phi) dphi for one tooth in the cut, shape ``phi.shape + (2, 2)`` [N/m^2 rad]."""
    phi = np.asarray(phi, dtype=float)
    kt, kn = setup.kt, setup.kn
    s2, c2 = np.sin(2.0 * phi), np.cos(2.0 * phi)
    out = np.empty((*phi.shape, 2, 2))
    out[..., 0, 0] = -0.25 * kt * c2 + 0.5 * kn * (phi - 0.5 * s2)
    out[..., 0, 1] = 0.5 * kt * (phi + 0.5 * s2) - 0.25 * kn * c2
    out[..., 1, 0] = -0.5 * kt * (phi - 0.5 * s2) - 0.25 * kn * c2
    out[..., 1, 1] = 0.25 * kt * c2 + 0.5 * kn * (phi + 0.5 * s2)
    return out


def directional_matrix(setup: MillingSetup) -> np.ndarray:
    """Mean directional matrix D [N/m^2] of the zero-order approximation, rows/columns (x, y).

    ``D = (1/T) int_0^T H(t) dt = -(N K_t / (4 pi)) [alpha]`` (Altintas and Budak 1995, Eq 12,
    the "average directional factors"); see the module docstring for [alpha].

    Parameters
    ----------
    setup : MillingSetup
        The milling set-up.

    Returns
    -------
    numpy.ndarray
        D, shape (2, 2) [N/m^2].

    Examples
    --------
    Full slot: the cross terms are -/+ N K_t / 4 and the direct terms N K_n / 4:

    >>> directional_matrix(MillingSetup(teeth=2, kt=6e8, kn=2e8)) / 1e8
    array([[ 1.,  3.],
           [-3.,  1.]])
    """
    st, ex = setup.entry_angle, setup.exit_angle
    kr = setup.kr_ratio

    def alpha(phi):
        s2, c2 = math.sin(2.0 * phi), math.cos(2.0 * phi)
        return 0.5 * np.array([
            [c2 - 2.0 * kr * phi + kr * s2, -s2 - 2.0 * phi + kr * c2],
            [-s2 + 2.0 * phi + kr * c2, -c2 - 2.0 * kr * phi - kr * s2]])

    return -(setup.teeth * setup.kt / (4.0 * math.pi)) * (alpha(ex) - alpha(st))


def directional_factor(setup: MillingSetup, direction: str = "x") -> float:
    """Oriented (directional) factor mu_d = D_dd / K_t [-] for one flexible direction.

    With only direction d flexible, the zero-order limit is ``b_lim = -1 / (2 K_t mu_d Re G_dd)``
    (Tlusty's form with K_s = K_t). mu_d may be negative for some engagements (then chatter
    needs Re G_dd > 0, i.e. frequencies below the resonance).

    Parameters
    ----------
    setup : MillingSetup
        The milling set-up.
    direction : {"x", "y"}, optional
        The flexible direction d (default "x").

    Returns
    -------
    float
        mu_d [-].

    Raises
    ------
    ValueError
        When ``direction`` is neither "x" nor "y".
    """
    i = _direction_index(direction)
    return float(directional_matrix(setup)[i, i] / setup.kt)


def _direction_index(direction: str) -> int:
    try:
        return DIRECTIONS.index(str(direction).lower())
    except ValueError:
        raise ValueError(f"direction must be 'x' (feed) or 'y', got {direction!r}") from None


def periodic_directional_matrix(setup: MillingSetup, intervals: int) -> np.ndarray:
    """Time averages of H(t) [N/m^2] over the ``intervals`` equal parts of one tooth period.

    Interval i covers ``[i T/m, (i+1) T/m]`` with tooth 0 at angle 0 at t = 0. The averages
    are exact (closed-form integrals of the trigonometric terms, clipped at the entry and exit
    angles), so a tooth entering or leaving the cut inside an interval is weighted correctly.
    They do not depend on the spindle speed: in one tooth period every tooth turns 2 pi / N.

    Parameters
    ----------
    setup : MillingSetup
        The milling set-up.
    intervals : int
        Number m of equal intervals of the tooth period, >= 1.

    Returns
    -------
    numpy.ndarray
        Shape ``(intervals, 2, 2)``; its mean over the intervals is :func:`directional_matrix`.

    Raises
    ------
    ValueError
        When ``intervals`` is not a whole number >= 1.

    Examples
    --------
    >>> s = MillingSetup(teeth=3, kt=6e8, kn=2e8, radial_immersion=0.3, milling="up")
    >>> bool(np.allclose(periodic_directional_matrix(s, 17).mean(axis=0), directional_matrix(s)))
    True
    """
    if isinstance(intervals, bool) or int(intervals) != intervals or intervals < 1:
        raise ValueError(f"intervals must be a whole number >= 1, got {intervals!r}")
    m, n_teeth = int(intervals), setup.teeth
    dphi = 2.0 * math.pi / (n_teeth * m)
    st, ex = setup.entry_angle, setup.exit_angle
    start = (np.arange(m)[:, None] * dphi
             + 2.0 * math.pi * np.arange(n_teeth)[None, :] / n_teeth) % (2.0 * math.pi)
    total = np.zeros((m, 2, 2))
    for shift in (0.0, 2.0 * math.pi):  # an interval may wrap past 2 pi
        a = np.clip(start - shift, st, ex)
        b = np.clip(start + dphi - shift, st, ex)
        total += (_antiderivative(setup, b) - _antiderivative(setup, a)).sum(axis=1)
    return total / dphi
