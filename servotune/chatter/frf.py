"""The tool/work-piece compliance as the chatter analysis needs it: a 2 x 2 FRF over x and y.

The compliance is the displacement of the tool *relative to* the work piece per unit cutting
force [m/N], in the plane of the cut: x is the feed direction, y the direction normal to it
(see :mod:`servotune.chatter.setup`). Every analysis in :mod:`servotune.chatter` works on the
2 x 2 matrix ``[[G_xx, G_xy], [G_yx, G_yy]]`` (outputs x, y; inputs F_x, F_y). It can come from

- a python-control ``StateSpace`` or ``TransferFunction``: 2 x 2 in that order, or SISO for one
  flexible direction (``direction="x"`` or ``"y"``; the other direction is then rigid);
- a python-control ``FrequencyResponseData`` (2 x 2 or SISO), e.g. a measurement read with
  :func:`read_frf_csv`;
- plain arrays ``(omega, H)``: omega [rad/s] and H of shape ``(nfreq,)`` (SISO) or
  ``(2, 2, nfreq)`` (python-control's layout).

A rigid direction is a zero row and column: for the zero-order method a SISO compliance in x is
exactly the 2 x 2 matrix with G_xx alone, and the semi-discretisation drops the rigid direction
from its state.

:func:`modal_compliance` builds the state-space compliance of uncoupled modes, the quick form of
the ``servotune lobes --mode`` command.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np

from ..tablefile import read_table
from ..validation import number, positive, positive_array
from .setup import DIRECTIONS, _direction_index

__all__ = [
    "FRF_CSV_TERMS",
    "Mode",
    "compliance_matrix",
    "frequency_grid",
    "modal_compliance",
    "read_frf_csv",
    "system_response",
]

#: CSV column stems of the four compliance terms (``re_xx_m_per_n``, ``im_xx_m_per_n``, ...)
FRF_CSV_TERMS = ("xx", "xy", "yx", "yy")


@dataclass(frozen=True)
class Mode:
    """One vibration mode of the tool/work-piece compliance in one direction.

    Parameters
    ----------
    natural_frequency : float
        Undamped natural frequency w_n [rad/s], > 0.
    damping_ratio : float
        Viscous damping ratio zeta [-], in (0, 1).
    stiffness : float
        Modal stiffness k [N/m], > 0: the static compliance of the mode is 1/k and its modal
        mass k / w_n^2.
    direction : {"x", "y"}
        The direction the mode moves (x = feed).

    Examples
    --------
    The milling benchmark of Insperger and Stepan (f_n = 922 Hz, modal mass 0.03993 kg):

    >>> wn = 2 * math.pi * 922.0
    >>> mode = Mode(wn, 0.011, 0.03993 * wn**2)
    >>> round(mode.mass, 5), round(mode.stiffness / 1e6, 4)
    (0.03993, 1.34)
    """

    natural_frequency: float
    damping_ratio: float
    stiffness: float
    direction: str = "x"

    def __post_init__(self) -> None:
        object.__setattr__(self, "natural_frequency", positive(
            "Mode", "natural_frequency", self.natural_frequency, "rad/s"))
        object.__setattr__(self, "stiffness", positive("Mode", "stiffness", self.stiffness, "N/m"))
        zeta = number("Mode", "damping_ratio", self.damping_ratio)
        if not 0.0 < zeta < 1.0:
            raise ValueError(f"Mode.damping_ratio must lie in (0, 1), got {self.damping_ratio!r}")
        object.__setattr__(self, "damping_ratio", zeta)
        object.__setattr__(self, "direction", DIRECTIONS[_direction_index(self.direction)])

    @classmethod
    def from_hz(cls, f_hz: float, damping_ratio: float, stiffness: float,
                direction: str = "x") -> Mode:
        """Return a mode given by its natural frequency in Hz (the command line's form).

        Parameters
        ----------
        f_hz : float
            Natural frequency [Hz].
        damping_ratio : float
            Modal damping ratio [-].
        stiffness : float
            Modal stiffness [N/m].
        direction : {"x", "y"}, optional
            Direction the mode acts in (default "x").

        Returns
        -------
        Mode
            The mode with natural frequency ``2 pi f_hz`` [rad/s].
        """
        return cls(2.0 * math.pi * float(f_hz), damping_ratio, stiffness, direction)

    @property
    def mass(self) -> float:
        """Modal mass k / w_n^2 [kg]."""
        return self.stiffness / self.natural_frequency ** 2


def modal_compliance(modes) -> control.StateSpace:
    """State-space compliance of uncoupled modes: inputs (fx, fy) [N], outputs (x, y) [m].

    Each mode adds the states (q, dq/dt) of ``m q'' + c q' + k q = F_d``, output d += q.

    Parameters
    ----------
    modes : iterable of Mode
        The modes, each acting in its own direction (x or y) with its own stiffness.

    Returns
    -------
    control.StateSpace
        2 x 2, inputs named ``fx, fy`` and outputs ``x, y``.

    Raises
    ------
    ValueError
        When no mode is given, or an item is not a :class:`Mode`.

    Examples
    --------
    The static compliance is the sum of the modal ones, 1/k:

    >>> sys = modal_compliance([Mode(100.0, 0.05, 2e6), Mode(300.0, 0.02, 4e6)])
    >>> float(sys.dcgain()[0, 0]) * 1e6
    0.75
    """
    modes = list(modes)
    if not modes:
        raise ValueError("give at least one mode")
    if not all(isinstance(m, Mode) for m in modes):
        raise ValueError("modes must be servotune.chatter.Mode objects")
    n = 2 * len(modes)
    a, b, c = np.zeros((n, n)), np.zeros((n, 2)), np.zeros((2, n))
    for i, mode in enumerate(modes):
        wn, zeta = mode.natural_frequency, mode.damping_ratio
        d = _direction_index(mode.direction)
        a[2 * i, 2 * i + 1] = 1.0
        a[2 * i + 1, 2 * i] = -wn * wn
        a[2 * i + 1, 2 * i + 1] = -2.0 * zeta * wn
        b[2 * i + 1, d] = 1.0 / mode.mass
        c[d, 2 * i] = 1.0
    return control.ss(a, b, c, np.zeros((2, 2)), inputs=["fx", "fy"], outputs=["x", "y"])


def _lti_poles(system) -> np.ndarray:
    return np.atleast_1d(np.asarray(system.poles(), dtype=complex))


def _check_stable(system) -> None:
    poles = _lti_poles(system)
    if poles.size and np.max(poles.real) >= 0.0:
        worst = poles[np.argmax(poles.real)]
        raise ValueError(
            f"the compliance has a pole at {worst:.4g} rad/s with non-negative real part: "
            "chatter stability needs a stable tool/work-piece compliance (close the servo loops "
            "and hold any rigid-body motion before analysing it)")


def frequency_grid(system, omega_max: float | None = None, points: int = 1500) -> np.ndarray:
    """A frequency grid [rad/s] that resolves every resonance of a python-control system.

    A logarithmic base grid from a fifth of the lowest natural frequency to five times the
    highest (or ``omega_max`` if higher) is merged with 801 points over
    ``w_n (1 + zeta t)``, t in [-10, 30], around each lightly damped pole, where the real part
    of the compliance has its negative lobe (width ~ zeta w_n).

    Parameters
    ----------
    system : control.LTI
        python-control system (state space or transfer function) whose poles are resolved.
    omega_max : float, optional
        Upper end of the grid [rad/s] when above five times the highest natural frequency.
    points : int, optional
        Points of the logarithmic base grid (default 1500).

    Returns
    -------
    numpy.ndarray
        Strictly increasing frequencies [rad/s], shape (n,).

    Raises
    ------
    ValueError
        When the system has no pole away from zero.

    Examples
    --------
    >>> from servotune.chatter import Mode, modal_compliance
    >>> w = frequency_grid(modal_compliance([Mode(5793.0, 0.011, 1.34e6)]))
    >>> bool(np.all(np.diff(w) > 0)), bool(w.min() < 5793.0 < w.max())
    (True, True)
    """
    poles = _lti_poles(system)
    poles = poles[np.abs(poles) > 0.0]
    if poles.size == 0:
        raise ValueError("the compliance has no poles away from zero: no resonance to analyse")
    wn = np.abs(poles)
    zeta = -poles.real / wn
    lo, hi = 0.2 * wn.min(), 5.0 * wn.max()
    if omega_max is not None:
        hi = max(hi, float(omega_max))
    parts = [np.geomspace(lo, hi, int(points))]
    t = np.linspace(-10.0, 30.0, 801)
    for w, z in zip(wn, zeta, strict=True):
        if 0.0 < z < 0.3:
            band = w * (1.0 + z * t)
            parts.append(band[(band > lo) & (band < hi)])
    return np.unique(np.concatenate(parts))


def system_response(system, omega) -> np.ndarray:
    """Frequency response (p, m, nfreq) of a python-control system at omega [rad/s].

    A state-space system with a well-conditioned eigenvector basis is evaluated as a sum of
    first-order terms, ``C V diag(1 / (i w - lambda)) V^-1 B + D``, which costs O(n) per
    frequency; anything else goes through python-control.

    Parameters
    ----------
    system : control.LTI
        python-control system with p outputs and m inputs.
    omega : array_like
        Angular frequencies [rad/s], shape (nfreq,).

    Returns
    -------
    numpy.ndarray
        Complex response, shape (p, m, nfreq).
    """
    omega = np.asarray(omega, dtype=float)
    if isinstance(system, control.StateSpace) and system.nstates > 0:
        lam, v = np.linalg.eig(system.A)
        if np.linalg.cond(v) < 1e8:
            left = system.C @ v                                  # (p, n)
            right = np.linalg.solve(v, system.B)                 # (n, m)
            resolvent = 1.0 / (1j * omega[None, :] - lam[:, None])  # (n, nfreq)
            out = np.einsum("pn,nf,nm->pmf", left, resolvent, right)
            return out + np.asarray(system.D, dtype=float)[:, :, None]
    return np.asarray(system(1j * omega, squeeze=False))


def _check_omega(omega) -> np.ndarray:
    omega = positive_array("", "omega", omega, "rad/s")
    if omega.ndim != 1 or omega.size < 3:
        raise ValueError("omega must be a 1-D array of at least 3 frequencies [rad/s]")
    if np.any(np.diff(omega) <= 0.0):
        i = int(np.argmax(np.diff(omega) <= 0.0))
        raise ValueError(f"omega must be strictly increasing [rad/s], got {float(omega[i])!r} "
                         f"then {float(omega[i + 1])!r} (at index {i + 1})")
    return omega


def _embed(h: np.ndarray, direction: str) -> np.ndarray:
    """SISO response (nfreq,) into the 2 x 2 matrix (nfreq, 2, 2) with one flexible direction."""
    d = _direction_index(direction)
    g = np.zeros((*h.shape, 2, 2), dtype=complex)
    g[:, d, d] = h
    return g


def _as_matrix(response: np.ndarray, direction: str, what: str) -> np.ndarray:
    """(p, m, nfreq) -> (nfreq, 2, 2)."""
    p, m = response.shape[:2]
    if (p, m) == (1, 1):
        return _embed(response[0, 0], direction)
    if (p, m) == (2, 2):
        return np.moveaxis(response, -1, 0).astype(complex)
    raise ValueError(f"{what} must be SISO or 2 x 2 (outputs x, y; inputs Fx, Fy), "
                     f"got {p} outputs x {m} inputs")


def compliance_matrix(system, omega=None, direction: str = "x"):
    """The 2 x 2 tool/work-piece compliance [m/N] on a frequency grid.

    Parameters
    ----------
    system : control.StateSpace, control.TransferFunction, control.FrequencyResponseData or
        tuple (omega, H)
        See the module docstring. A 2 x 2 system is read as outputs (x, y), inputs (Fx, Fy).
    omega : array_like, optional
        Frequencies [rad/s] at which to evaluate a state-space or transfer-function system;
        default :func:`frequency_grid`. Not allowed with measured data, which carries its own.
    direction : {"x", "y"}
        The flexible direction of a SISO compliance.

    Returns
    -------
    (omega, G) : tuple of numpy.ndarray
        omega [rad/s], shape (nfreq,); G [m/N], shape (nfreq, 2, 2).

    Raises
    ------
    ValueError
        For an unstable system, a shape that is neither SISO nor 2 x 2, a bad frequency grid,
        or non-finite data.
    """
    _direction_index(direction)
    if isinstance(system, control.FrequencyResponseData):
        if omega is not None:
            raise ValueError("a FrequencyResponseData carries its own frequencies; do not pass "
                             "omega")
        w = _check_omega(system.omega)
        g = _as_matrix(np.asarray(system(1j * w, squeeze=False)), direction,
                       "the FrequencyResponseData")
    elif isinstance(system, (control.StateSpace, control.TransferFunction)):
        _check_stable(system)
        w = _check_omega(frequency_grid(system) if omega is None else omega)
        g = _as_matrix(system_response(system, w), direction, "the system")
    elif isinstance(system, tuple) and len(system) == 2:
        if omega is not None:
            raise ValueError("arrays (omega, H) carry their own frequencies; do not pass omega")
        w = _check_omega(system[0])
        h = np.asarray(system[1], dtype=complex)
        if h.shape == w.shape:
            g = _embed(h, direction)
        elif h.shape == (2, 2, w.size):
            g = np.moveaxis(h, -1, 0)
        else:
            raise ValueError(f"H must have shape ({w.size},) or (2, 2, {w.size}) to match "
                             f"omega, got {h.shape}")
    else:
        raise ValueError("the compliance must be a python-control StateSpace, TransferFunction "
                         "or FrequencyResponseData, or a tuple (omega, H); got "
                         f"{type(system).__name__}")
    if not np.all(np.isfinite(g)):
        raise ValueError("the compliance contains non-finite values")
    return w, g


def read_frf_csv(path) -> control.FrequencyResponseData:
    """Read a measured compliance from a CSV file into a 2 x 2 FrequencyResponseData.

    The header names the columns: ``f_hz`` and, for each measured term ij in xx, xy, yx, yy,
    the pair ``re_ij_m_per_n, im_ij_m_per_n`` [m/N]. At least xx or yy must be present; a
    missing direct term means a rigid direction, missing cross terms mean no coupling (give
    both xy and yx or neither). Lines starting with ``#`` are comments.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    control.FrequencyResponseData
        2 x 2, inputs ``fx, fy``, outputs ``x, y``; omega = 2 pi f_hz.

    Raises
    ------
    servotune.tablefile.TableFileError
        When the file cannot be read, or naming the missing or unexpected columns, or the
        line of a bad value.
    """
    table = read_table(path, "measured FRF", min_rows=3,
                       hint="f_hz and re_ij_m_per_n, im_ij_m_per_n for ij in xx, xy, yx, yy")
    header = table.header
    expected = {"f_hz"} | {f"{p}_{t}_m_per_n" for t in FRF_CSV_TERMS for p in ("re", "im")}
    unknown = sorted(set(header) - expected)
    if unknown:
        raise table.error(f"unknown columns {unknown}; expected f_hz and "
                          "re_ij_m_per_n, im_ij_m_per_n for ij in xx, xy, yx, yy")
    table.require("f_hz", hint="the frequency in Hz")
    for i, r in enumerate(table.rows):
        if len(r) != len(header):
            raise table.error(f"every row must have {len(header)} values, this one has "
                              f"{len(r)}", i)
    col = {name: table.numbers(name) for name in header}
    present = []
    for term in FRF_CSV_TERMS:
        pair = [f"re_{term}_m_per_n" in col, f"im_{term}_m_per_n" in col]
        if any(pair) and not all(pair):
            raise table.error(f"give both re_{term}_m_per_n and im_{term}_m_per_n")
        if all(pair):
            present.append(term)
    if not {"xx", "yy"} & set(present):
        raise table.error("need at least the direct term xx or yy")
    if ("xy" in present) != ("yx" in present):
        raise table.error("give both cross terms xy and yx, or neither")
    omega = _check_omega(2.0 * math.pi * col["f_hz"])
    response = np.zeros((2, 2, omega.size), dtype=complex)
    for term in present:
        i, j = _direction_index(term[0]), _direction_index(term[1])
        response[i, j] = col[f"re_{term}_m_per_n"] + 1j * col[f"im_{term}_m_per_n"]
    if not np.all(np.isfinite(response)):
        raise ValueError(f"{path}: the compliance contains non-finite values")
    return control.frd(response, omega, inputs=["fx", "fy"], outputs=["x", "y"])
