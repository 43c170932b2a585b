"""Check a reduced model against the full FE model it came from.

In the spirit of pyyeti's ``cb.cbcheck``, but against the full model: a reduction is right when

* its natural frequencies in the band of interest are those of the full model (the full
  model's lowest modes are computed independently, by shift-invert Lanczos on the full
  matrices with a Sturm-counted number of modes; Rayleigh-Ritz makes the reduced ones come out
  at or above them);
* its driving-point compliance at every port (boundary DOF) over the band is the full model's:
  the local peak near every resonance of either model (and the band peak) compared, so that
  a lost or spurious resonance, a wrong peak height or a peak that moved out of place shows,
  while anti-resonances (where relative errors mean nothing) do not; the full model's
  compliance comes from its own modes up to ``reference_factor`` times the top of the band
  plus the exact static remainder of the modes left out (below);
* its kept fixed-interface modes cover the band with a margin
  (:func:`~servotune.structure.mode_coverage`);

and it reports the modal effective mass the kept fixed-interface modes capture in each
rigid-body direction (informative: pyyeti's ``cbcheck`` table).

Both compliances use structural damping ``K (1 + j eta)``, eta = 2 zeta, which projects exactly
onto the reduced model (K_r (1 + j eta)), so that the two are compared under the same damping.

Notes
-----
Full model, modes phi_j (lambda_j = omega_j^2) below the reference frequency, shift sigma < 0
of the spectral transformation, X_1 = (K - sigma M)^-1 P with P the unit columns at the ports
and X_(i+1) = (K - sigma M)^-1 M X_i, so that X_i^T M X_j = sum over all modes of
phi phi^T / (lambda - sigma)^(i+j)::

    H(w) = sum_j phi_j phi_j^T / (lambda_j (1 + j eta) - w^2)
           + sum_p (w^2 / (1 + j eta) - sigma)^p R_p / (1 + j eta)
    R_p = P^T (K - sigma M)^-1 (M (K - sigma M)^-1)^p P - sum_j phi_j phi_j^T
          / (lambda_j - sigma)^(p+1)                 (the modes left out, exactly)

The remainder of the modes left out is the series 1/(lambda - w^2) = sum_p (w^2 - sigma)^p /
(lambda - sigma)^(p+1), with the structural damping of those modes as 1/(lambda (1 + j eta) -
w^2) = 1/(1 + j eta) / (lambda - w^2/(1 + j eta)), kept to ``REMAINDER_ORDER`` = 4 terms:
with the reference modes up to twice the top of the band the neglected part is at most
r^4 / (1 - r) = 1/192 of the remainder (r = (w^2 - sigma)/(lambda - sigma) <= about 1/4).
Rigid-body modes (the same in both models) are left out of the compared compliance, whose mass
line would hide the resonances of a free port.

References
----------
T. P. Widrick, pyYeti, ``pyyeti.cb.cbcheck`` (checks of Craig-Bampton models).
R. R. Craig, A. J. Kurdila, Fundamentals of Structural Dynamics, 2nd ed., Wiley (2006), sec
13.4 (mode-acceleration and static correction of truncated modal sums).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse

from ..units import RAD_S_PER_HZ
from .cbcheck import rigid_body_vectors
from .coverage import DEFAULT_MARGIN, BandCoverage, mode_coverage
from .model import ModalModel
from .solvers import factorise, lowest_modes

__all__ = ["COMPLIANCE_FLOOR", "ReductionCheck", "reduction_check"]

#: Peaks below this share of a port's largest compliance in the band are not compared.
COMPLIANCE_FLOOR = 0.01
#: Terms of the series in (w^2 - sigma) for the remainder of the full model's modes left out.
REMAINDER_ORDER = 4
#: Eigenvalues below this share of the largest computed one are rigid-body modes.
RIGID_SHARE = 1e-10


def _finite_list(a):
    return [float(x) if math.isfinite(x) else None for x in np.asarray(a, dtype=float).ravel()]


@dataclass(frozen=True, eq=False)
class ReductionCheck:
    """What :func:`reduction_check` found; ``str()`` gives a readable report.

    Attributes
    ----------
    coverage : BandCoverage
        The kept fixed-interface modes against the band.
    full_frequencies_hz, reduced_frequencies_hz : ndarray
        Natural frequencies of the full model up to the top of the band and the reduced
        model's first as many [Hz] (rigid-body modes included, as 0 or near it).
    frequency_errors : ndarray
        reduced / full - 1 of each flexible mode in the band.
    n_missing_modes : int
        Full-model modes in the band that the reduced model has no counterpart for (it has
        fewer modes there).
    rigid_body_modes_full, rigid_body_modes_reduced : int
    ports : tuple of str
        The boundary DOFs whose driving-point compliance was compared.
    compliance_errors : ndarray
        Per port, the largest |peak_red / peak_full - 1| of the local compliance peaks (the
        largest |H| within +-max(3 zeta, 2 frequency_tolerance) of every resonance of either
        model in the band and of the band peak of either), over the peaks that reach
        ``COMPLIANCE_FLOOR`` of the port's largest compliance in the band.
    peak_full, peak_reduced : ndarray
        Per port, the largest |H| over the band [m/N, rad/(N m)].
    directions : tuple of str
        Rigid-body directions of the effective mass (empty without them).
    effective_mass_fraction : ndarray or None
        Per direction, the modal effective mass of the kept fixed-interface modes over the
        rigid-body mass.
    reference_modes : int
        Full-model modes computed (up to ``reference_factor`` times the top of the band).
    reference_method : str
        "dense" or "lanczos" (Sturm-counted).
    frequency_tolerance, compliance_tolerance : float
    failures : tuple of str
        One sentence per failed item, each with its fix.
    """

    coverage: BandCoverage
    full_frequencies_hz: np.ndarray
    reduced_frequencies_hz: np.ndarray
    frequency_errors: np.ndarray
    n_missing_modes: int
    rigid_body_modes_full: int
    rigid_body_modes_reduced: int
    ports: tuple[str, ...]
    compliance_errors: np.ndarray
    peak_full: np.ndarray
    peak_reduced: np.ndarray
    directions: tuple[str, ...]
    effective_mass_fraction: np.ndarray | None
    reference_modes: int
    reference_method: str
    frequency_tolerance: float
    compliance_tolerance: float
    failures: tuple[str, ...]

    @property
    def passed(self) -> bool:
        """Frequencies and port compliance within tolerance, no mode missing, the same rigid
        body modes, and the band covered by the kept fixed-interface modes."""
        return not self.failures

    @property
    def max_frequency_error(self) -> float:
        """Largest |reduced / full - 1| over the flexible modes in the band (0 with none)."""
        return float(np.abs(self.frequency_errors).max(initial=0.0))

    @property
    def max_compliance_error(self) -> float:
        """Largest compliance error over the ports."""
        return float(np.max(self.compliance_errors, initial=0.0))

    def to_dict(self) -> dict:
        """Plain values for JSON (SI; frequencies in Hz as the names say).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        worst = int(np.argmax(self.compliance_errors)) if self.ports else None
        return {
            "passed": self.passed, "failures": list(self.failures),
            "band_coverage": self.coverage.to_dict(),
            "full_frequencies_hz": _finite_list(self.full_frequencies_hz),
            "reduced_frequencies_hz": _finite_list(self.reduced_frequencies_hz),
            "frequency_errors": _finite_list(self.frequency_errors),
            "max_frequency_error": self.max_frequency_error,
            "frequency_tolerance": self.frequency_tolerance,
            "n_missing_modes": self.n_missing_modes,
            "rigid_body_modes_full": self.rigid_body_modes_full,
            "rigid_body_modes_reduced": self.rigid_body_modes_reduced,
            "ports": list(self.ports),
            "compliance_errors": _finite_list(self.compliance_errors),
            "max_compliance_error": self.max_compliance_error,
            "worst_port": None if worst is None else self.ports[worst],
            "compliance_tolerance": self.compliance_tolerance,
            "peak_compliance_full": _finite_list(self.peak_full),
            "peak_compliance_reduced": _finite_list(self.peak_reduced),
            "directions": list(self.directions),
            "effective_mass_fraction": None if self.effective_mass_fraction is None
            else _finite_list(self.effective_mass_fraction),
            "reference_modes": self.reference_modes,
            "reference_method": self.reference_method,
        }

    def __str__(self) -> str:
        lo, hi = self.coverage.band_hz
        lines = [f"Reduced against full model over {lo:g}-{hi:g} Hz "
                 f"({self.reference_modes} full-model modes, {self.reference_method})",
                 f"  band coverage: {self.coverage.message}"]
        lines.append(f"  rigid-body modes: full {self.rigid_body_modes_full}, reduced "
                     f"{self.rigid_body_modes_reduced}")
        if self.full_frequencies_hz.size:
            lines.append("  mode   full [Hz]   reduced [Hz]   error")
            for j, f in enumerate(self.full_frequencies_hz):
                if j < self.reduced_frequencies_hz.size:
                    fr = self.reduced_frequencies_hz[j]
                    err = fr / f - 1 if f > 1e-4 * hi else 0.0
                    flag = "" if abs(err) <= self.frequency_tolerance else "  <- off"
                    lines.append(f"  {j + 1:4d} {f:11.5g} {fr:14.5g} {100 * err:8.3f} %{flag}")
                else:
                    lines.append(f"  {j + 1:4d} {f:11.5g}        missing")
        else:
            lines.append("  the full model has no mode in the band")
        if self.ports:
            lines.append("  port            peak full     peak reduced   compliance error")
            for p, a, b, e in zip(self.ports, self.peak_full, self.peak_reduced,
                                  self.compliance_errors, strict=True):
                flag = "" if e <= self.compliance_tolerance else "  <- off"
                lines.append(f"  {p:14s} {a:12.4e} {b:14.4e} {100 * e:12.2f} %{flag}")
        if self.effective_mass_fraction is not None:
            lines.append("  effective mass of the kept fixed-interface modes: "
                         + ", ".join(f"{d} {100 * v:.1f} %" for d, v in
                                     zip(self.directions, self.effective_mass_fraction,
                                         strict=True)))
        for f in self.failures:
            lines.append(f"  FAILED: {f}")
        lines.append(f"  result: {'passed' if self.passed else 'FAILED'}")
        return "\n".join(lines)


def _full_reference(k, m, b, band_top, reference_factor, shift, solver):
    """The full model's modes up to reference_factor x band top and the remainder terms
    R_p = sum over the modes left out of phi phi^T / (lambda - shift)^(p+1) at the ports."""
    # lazy: the Sturm count that sizes the Lanczos run comes first and does not share the
    # memory with these factors
    factor = factorise(k - shift * m, solver, name="K - sigma M of the full model",
                       mechanism="the full model K - sigma M is singular (sigma < 0): check "
                                 "the mass matrix (every DOF that can move needs mass)",
                       lazy=True)
    modes = lowest_modes(k, m, below=(reference_factor * band_top) ** 2, shift=shift,
                         factor=factor, solver=solver, name="K of the full model")
    lam, phi = modes.eigenvalues, modes.vectors
    mphi = m @ phi

    def deflate(y):  # the components along the kept modes out (M-orthogonal projection)
        return y - phi @ (mphi.T @ y)

    p = np.zeros((k.shape[0], b.size))
    p[b, np.arange(b.size)] = 1.0
    # Y_1 = Q (K - sM)^-1 P, Y_j+1 = Q (K - sM)^-1 M Y_j with Q the projection: then
    # Y_i^T M Y_j = sum over the modes left out of phi_b phi_b^T / (l - s)^(i+j), without the
    # cancellation that subtracting the kept modes from the full sums would suffer
    ys = [deflate(factor.solve(p))]
    for _ in range(REMAINDER_ORDER // 2 - 1):
        ys.append(deflate(factor.solve(m @ ys[-1])))
    factor.release()
    pb = phi[b]                                                   # (n_b, r)
    remainder = []
    for order in range(REMAINDER_ORDER):
        if order == 0:
            r = ys[0][b]
        else:
            i, j = (order - 1) // 2, order // 2
            r = ys[i].T @ (m @ ys[j])
        remainder.append(np.diag(0.5 * (r + r.T)).copy())
    return lam, pb, np.array(remainder), modes.method


def _driving_points(lam, shapes, eta, omega, remainder=None, shift=0.0, flexible_only=False):
    """|H_pp(w)| for every port p: modal sum with structural damping (+ the remainder of the
    modes left out, as a series in (w^2 - shift)); rigid-body modes left out on request."""
    if flexible_only:
        keep = lam > RIGID_SHARE * max(float(np.max(lam, initial=0.0)), 1e-300)
        lam, shapes = lam[keep], shapes[:, keep]
    den = lam[None, :] * (1 + 1j * eta) - omega[:, None] ** 2        # (f, r)
    h = (1.0 / den) @ (shapes.T ** 2)                                  # (f, n_b)
    if remainder is not None:
        # 1/(l (1 + j eta) - w^2) = 1/(1 + j eta) / (l - w~^2), w~^2 = w^2 / (1 + j eta)
        z = omega[:, None] ** 2 / (1 + 1j * eta) - shift
        for order, r in enumerate(remainder):
            h = h + z**order * r[None, :] / (1 + 1j * eta)
    return np.abs(h)


def reduction_check(mass, stiffness, boundary, reduced: ModalModel, band, *,
                    margin: float = DEFAULT_MARGIN, damping_ratio: float = 0.03,
                    coordinates=None, rigid_body=None, reference=(0.0, 0.0, 0.0),
                    frequency_tolerance: float = 0.01, compliance_tolerance: float = 0.05,
                    reference_factor: float = 2.0, n_points: int = 400,
                    solver: str = "auto") -> ReductionCheck:
    """Check a reduced model against the full FE model over a frequency band.

    Parameters
    ----------
    mass, stiffness : (n, n) sparse matrix or array_like
        The full model (as given to :func:`~servotune.structure.craig_bampton`).
    boundary : sequence of int
        The boundary DOF indices of the reduction, in the order of the reduced model's
        physical DOFs.
    reduced : ModalModel
        The reduced model: its physical (not ``mode.*``) DOFs are the boundary DOFs, first and
        in the order of ``boundary``.
    band : (float, float)
        Frequency band of interest [rad/s] (``Requirements.band``).
    margin : float
        Coverage margin of the kept fixed-interface modes (see :func:`mode_coverage`).
    damping_ratio : float
        zeta of the structural damping eta = 2 zeta used for both compliances.
    coordinates : mapping node -> (x, y, z), optional
        Node positions [m] for geometric rigid-body motions of the boundary DOFs (names
        ``<node>.<direction>``), for the effective mass.
    rigid_body : (n_b, n_rb) array_like, optional
        The rigid-body motions of the boundary DOFs given directly instead.
    reference : (3,) array_like
        Reference point of the geometric rigid-body motions [m].
    frequency_tolerance : float
        Largest accepted |f_reduced / f_full - 1| in the band (default 1 %).
    compliance_tolerance : float
        Largest accepted error of a compliance peak at a port (default 5 %).
    reference_factor : float
        The full model's modes are computed up to this times the top of the band.
    n_points : int
        Log-spaced frequencies over the band where the peaks are searched.
    solver : {"auto", "superlu", "pardiso"}
        Factorisation of the full model.

    Returns
    -------
    ReductionCheck
    """
    m = scipy.sparse.csc_array(mass, dtype=float)
    k = scipy.sparse.csc_array(stiffness, dtype=float)
    if m.shape != k.shape or m.shape[0] != m.shape[1]:
        raise ValueError(f"mass {m.shape} and stiffness {k.shape} must be square and alike")
    b = np.asarray(boundary, dtype=int).ravel()
    physical = [d for d in reduced.dofs if not d.startswith("mode.")]
    if len(physical) != b.size or tuple(reduced.dofs[:b.size]) != tuple(physical):
        raise ValueError(f"the reduced model's physical DOFs {physical} must come first and "
                         f"match the {b.size} boundary DOFs")
    lo, hi = (float(x) for x in band)
    if not (0 < lo < hi and math.isfinite(hi)):
        raise ValueError(f"band must be 0 < low < high [rad/s], got {band!r}")
    if not (0 <= damping_ratio < 0.5):
        raise ValueError(f"damping_ratio must lie in [0, 0.5), got {damping_ratio!r}")
    if reference_factor < 1.5:
        raise ValueError("reference_factor must be >= 1.5 (the full model's modes beyond "
                         "the band make its compliance reference)")
    coverage = mode_coverage(reduced, band, margin)
    shift = -lo * lo  # the full model may be free: shift below its rigid-body modes
    lam_f, pb_f, rem, method = _full_reference(k, m, b, hi, reference_factor, shift, solver)
    omega_f = np.sqrt(np.clip(lam_f, 0.0, None))
    rigid_tol = 1e-4 * hi
    in_band = omega_f <= hi
    full_hz = omega_f[in_band] / RAD_S_PER_HZ
    omega_r = reduced.natural_frequencies()
    phi_r = reduced.mode_shapes()[:b.size]
    reduced_hz = omega_r[:full_hz.size] / RAD_S_PER_HZ
    n_missing = int(full_hz.size - reduced_hz.size)
    rigid_full = int(np.sum(omega_f < rigid_tol))
    rigid_red = int(np.sum(omega_r < rigid_tol))
    pairs = min(full_hz.size, reduced_hz.size)
    flexible = full_hz[:pairs] > rigid_tol / RAD_S_PER_HZ
    errors = reduced_hz[:pairs][flexible] / full_hz[:pairs][flexible] - 1.0

    # compliance at the ports, both with structural damping eta = 2 zeta: the peaks near
    # every resonance of either model in the band and near the band peak of either
    eta = 2.0 * damping_ratio
    grid = np.geomspace(lo, hi, n_points)
    # the rigid-body modes are the same in both (Craig-Bampton keeps them exactly) and their
    # mass line would dwarf the resonances of a free port: compared are the flexible parts
    h_full = _driving_points(lam_f, pb_f, eta, grid, rem, shift, flexible_only=True)
    h_red = _driving_points(omega_r**2, phi_r, eta, grid, flexible_only=True)
    centres = np.unique(np.concatenate([
        omega_f[(omega_f >= lo) & in_band], omega_r[(omega_r >= lo) & (omega_r <= hi)],
        grid[np.argmax(h_full, axis=0)], grid[np.argmax(h_red, axis=0)]]))
    half = max(3.0 * damping_ratio, 2.0 * frequency_tolerance, 1e-3)
    local = centres[:, None] * np.geomspace(1.0 - half, 1.0 + half, 41)[None, :]
    local = np.clip(local, lo, hi).ravel()
    shape = (centres.size, 41, b.size)
    pf = _driving_points(lam_f, pb_f, eta, local, rem, shift,
                         flexible_only=True).reshape(shape).max(axis=1)
    pr = _driving_points(omega_r**2, phi_r, eta, local,
                         flexible_only=True).reshape(shape).max(axis=1)
    floor = COMPLIANCE_FLOOR * np.maximum(h_full.max(axis=0), h_red.max(axis=0))
    seen = np.maximum(pf, pr) >= floor[None, :]
    comp_err = np.where(seen, np.abs(pr / pf - 1.0), 0.0).max(axis=0, initial=0.0)

    directions, fraction = (), None
    if coordinates is not None or rigid_body is not None:
        if coordinates is not None and rigid_body is not None:
            raise ValueError("give either coordinates or rigid_body, not both")
        if coordinates is not None:
            r = rigid_body_vectors(physical, coordinates, reference)
            used = np.abs(r).sum(axis=0) > 0
            r = r[:, used]
            directions = tuple(d for d, u in zip(("X", "Y", "Z", "RX", "RY", "RZ"), used,
                                                 strict=True) if u)
        else:
            r = np.asarray(rigid_body, dtype=float).reshape(b.size, -1)
            directions = tuple(f"rb{j + 1}" for j in range(r.shape[1]))
        q = np.array([i for i, d in enumerate(reduced.dofs) if d.startswith("mode.")], int)
        rb_mass = np.diag(r.T @ reduced.mass[:b.size, :b.size] @ r)
        if q.size:
            lq = reduced.mass[np.ix_(q, np.arange(b.size))] @ r
            eff = (lq**2 / np.diag(reduced.mass)[q][:, None]).sum(axis=0)
        else:
            eff = np.zeros(r.shape[1])
        with np.errstate(divide="ignore", invalid="ignore"):
            fraction = np.where(rb_mass > 0, eff / rb_mass, 0.0)

    # the fix: cover the band first; when it is covered and still off, double the cut-off
    if not coverage.covered:
        more = math.ceil(coverage.required_hz)
    elif math.isfinite(coverage.complete_below_hz):
        more = math.ceil(2.0 * coverage.complete_below_hz)
    else:
        more = math.ceil(coverage.required_hz)
    failures = []
    if not coverage.covered:
        failures.append(coverage.message)
    if n_missing > 0:
        failures.append(f"the full model has {full_hz.size} modes up to {hi / RAD_S_PER_HZ:g} Hz, "
                        f"the reduced model only {reduced_hz.size}: add boundary DOFs or "
                        "fixed-interface modes")
    if rigid_full != rigid_red:
        failures.append(f"{rigid_full} rigid-body modes in the full model, {rigid_red} in the "
                        "reduced one: check the boundary DOFs and the supports")
    bad = np.flatnonzero(np.abs(errors) > frequency_tolerance)
    if bad.size:
        j = int(bad[np.argmax(np.abs(errors[bad]))])
        idx = np.flatnonzero(flexible)[j]
        failures.append(
            f"{bad.size} reduced natural frequencies in the band are off by more than "
            f"{100 * frequency_tolerance:g} % (mode {idx + 1}: {reduced_hz[idx]:.5g} Hz "
            f"against {full_hz[idx]:.5g} Hz, {100 * errors[j]:+.1f} %): modes were lost or "
            f"too few fixed-interface modes were kept; reduce with f_max_hz = {more}")
    worst = int(np.argmax(comp_err)) if comp_err.size else None
    if worst is not None and comp_err[worst] > compliance_tolerance:
        failures.append(
            f"the compliance at {physical[worst]} differs from the full model's by "
            f"{100 * comp_err[worst]:.1f} % in the band (tolerance "
            f"{100 * compliance_tolerance:g} %): keep more fixed-interface modes "
            f"(f_max_hz = {more})")
    return ReductionCheck(
        coverage=coverage, full_frequencies_hz=full_hz, reduced_frequencies_hz=reduced_hz,
        frequency_errors=errors, n_missing_modes=max(n_missing, 0),
        rigid_body_modes_full=rigid_full, rigid_body_modes_reduced=rigid_red,
        ports=tuple(physical), compliance_errors=comp_err, peak_full=h_full.max(axis=0),
        peak_reduced=h_red.max(axis=0), directions=directions,
        effective_mass_fraction=fraction, reference_modes=int(lam_f.size),
        reference_method=method, frequency_tolerance=float(frequency_tolerance),
        compliance_tolerance=float(compliance_tolerance), failures=tuple(failures))
