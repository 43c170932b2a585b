"""The check report of a reduced (or any) structural model, in the spirit of pyyeti's
``cb.cbcheck``: symmetry, definiteness, rigid-body mass and centre of gravity, fixed-base
frequencies and modal effective mass.

References
----------
R. R. Craig, A. J. Kurdila, Fundamentals of Structural Dynamics, 2nd ed., Wiley (2006), ch 18.
T. P. Widrick, pyYeti, ``pyyeti.cb.cbcheck`` (checks of Craig-Bampton models).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse

from ..units import RAD_S_PER_HZ
from .model import ModalModel
from .ports import normalise_direction

__all__ = ["CraigBamptonCheck", "cb_check", "rigid_body_vectors"]

_TRANSLATIONS = {"x": 0, "y": 1, "z": 2}
_ROTATIONS = {"rx": 0, "ry": 1, "rz": 2}
#: a ratio below this is taken as a negative eigenvalue of K (round-off allowance)
STIFFNESS_RATIO_TOLERANCE = 1e-9


def rigid_body_vectors(dofs, coordinates, reference=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Return the geometric rigid-body motions of named DOFs.

    A DOF named ``<node>.<x|y|z|rx|ry|rz>`` whose node is in ``coordinates`` (a mapping
    node -> (x, y, z) [m]) moves as a point of a rigid body: a translation t and a small
    rotation theta displace the point p by t + theta x (p - reference). The direction may also
    be spelt as an FE export does (``ux``, ``rotz``, Nastran components ``1``-``6``; see
    :func:`~servotune.structure.ports.normalise_direction`). Any other DOF (modal
    coordinates, relative or drive DOFs) gets a zero row.

    Parameters
    ----------
    dofs : sequence of str
        DOF names, ``<node>.<direction>``.
    coordinates : mapping
        Node name -> position (x, y, z) [m].
    reference : array_like, optional
        Point (x, y, z) [m] the rotations are taken about (default the origin).

    Returns
    -------
    numpy.ndarray
        Shape (n, 6): columns the translations along X, Y, Z [m/m] and the rotations about
        X, Y, Z through ``reference`` [m/rad for translation DOFs, rad/rad for rotation DOFs].

    Raises
    ------
    ValueError
        When ``reference`` or a node's coordinates are not 3 finite numbers.

    Examples
    --------
    A point 2 m along Y moves -2 m in X when the body turns 1 rad about Z:

    >>> r = rigid_body_vectors(["n1.x", "n1.y"], {"n1": (0.0, 2.0, 0.0)})
    >>> r[0].tolist()
    [1.0, 0.0, 0.0, 0.0, 0.0, -2.0]
    """
    ref = np.asarray(reference, dtype=float)
    if ref.shape != (3,):
        raise ValueError(f"reference must be a point (x, y, z), got {reference!r}")
    coords = {str(k): np.asarray(v, dtype=float) for k, v in dict(coordinates).items()}
    for node, p in coords.items():
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"coordinates of node {node!r} must be 3 finite numbers, got {p}")
    out = np.zeros((len(dofs), 6))
    for row, name in enumerate(dofs):
        node, _, comp = str(name).rpartition(".")
        if node not in coords:
            continue
        comp = normalise_direction(comp) or comp
        r = coords[node] - ref
        if comp in _TRANSLATIONS:
            e = np.eye(3)[_TRANSLATIONS[comp]]
            out[row, :3] = e
            out[row, 3:] = np.cross(r, e)  # e . (theta x r) = theta . (r x e)
        elif comp in _ROTATIONS:
            out[row, 3 + _ROTATIONS[comp]] = 1.0
    return out


@dataclass(frozen=True, eq=False)
class CraigBamptonCheck:
    """What :func:`cb_check` found; ``str()`` gives a readable report.

    Attributes
    ----------
    n_boundary, n_modes : int
        Boundary (physical) and modal DOFs of the model.
    mass_asymmetry, stiffness_asymmetry : float
        max |A - A^T| / max |A|.
    mass_eigenvalue_ratio, stiffness_eigenvalue_ratio : float
        Smallest eigenvalue over the largest in magnitude (M must be > 0, K >= 0 to
        round-off). The same values are readable under their former names
        ``mass_min_eigenvalue`` and ``stiffness_min_eigenvalue``.
    mass_positive_definite, stiffness_positive_semidefinite : bool
    free_free_frequencies_hz : ndarray
        Lowest natural frequencies of the model with nothing held [Hz] (rigid-body modes ~ 0).
    fixed_base_frequencies_hz : ndarray
        Natural frequencies with the boundary DOFs held [Hz].
    directions : tuple of str
        Labels of the rigid-body motions.
    rigid_body_mass : ndarray or None
        R^T M_bb R: the mass matrix of the rigid-body motions (6x6 about the reference point for
        geometric ones) [kg, kg m, kg m^2].
    center_of_gravity : ndarray or None
        From the geometric rigid-body mass [m], relative to the reference point.
    rigid_body_stiffness_residual : float or None
        max |K_bb R| / (max |K| max |R|): a rigid-body motion must not strain the model
        (grounding check).
    effective_mass : ndarray or None
        (n_modes, n_rb) modal effective mass L^2 / m_j, L = M_qb R [kg, kg m^2].
    effective_mass_fraction : ndarray or None
        Effective mass over the rigid-body mass of each direction.
    """

    n_boundary: int
    n_modes: int
    mass_asymmetry: float
    stiffness_asymmetry: float
    mass_eigenvalue_ratio: float
    stiffness_eigenvalue_ratio: float
    mass_positive_definite: bool
    stiffness_positive_semidefinite: bool
    free_free_frequencies_hz: np.ndarray
    fixed_base_frequencies_hz: np.ndarray
    directions: tuple
    rigid_body_mass: np.ndarray | None
    center_of_gravity: np.ndarray | None
    rigid_body_stiffness_residual: float | None
    effective_mass: np.ndarray | None
    effective_mass_fraction: np.ndarray | None

    @property
    def mass_min_eigenvalue(self) -> float:
        """Former name of :attr:`mass_eigenvalue_ratio` (it is a ratio of eigenvalues)."""
        return self.mass_eigenvalue_ratio

    @property
    def stiffness_min_eigenvalue(self) -> float:
        """Former name of :attr:`stiffness_eigenvalue_ratio`."""
        return self.stiffness_eigenvalue_ratio

    @property
    def passed(self) -> bool:
        """Symmetric to 1e-8, M > 0, K >= 0, rigid-body motions strain-free to 1e-6."""
        ok = (self.mass_asymmetry < 1e-8 and self.stiffness_asymmetry < 1e-8
              and self.mass_positive_definite and self.stiffness_positive_semidefinite)
        if self.rigid_body_stiffness_residual is not None:
            ok = ok and self.rigid_body_stiffness_residual < 1e-6
        return bool(ok)

    def to_dict(self) -> dict:
        """Plain values for JSON (SI; frequencies in Hz as the names say).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        out = {}
        for key in self.__dataclass_fields__:
            value = getattr(self, key)
            out[key] = value.tolist() if isinstance(value, np.ndarray) else value
        out["directions"] = list(self.directions)
        out["passed"] = self.passed
        return out

    def __str__(self) -> str:
        def yes(flag):
            return "ok" if flag else "FAILED"

        lines = [
            f"Craig-Bampton model check: {self.n_boundary} boundary DOFs, {self.n_modes} modes",
            f"  symmetry      M: max|M-M^T|/max|M| = {self.mass_asymmetry:.2e} "
            f"({yes(self.mass_asymmetry < 1e-8)})",
            f"                K: max|K-K^T|/max|K| = {self.stiffness_asymmetry:.2e} "
            f"({yes(self.stiffness_asymmetry < 1e-8)})",
            f"  definiteness  M: min/max eigenvalue = {self.mass_eigenvalue_ratio:.2e} "
            f"({yes(self.mass_positive_definite)}: must be > 0)",
            f"                K: min/max eigenvalue = {self.stiffness_eigenvalue_ratio:.2e} "
            f"({yes(self.stiffness_positive_semidefinite)}: must be >= 0)",
            "  free-free frequencies [Hz]: "
            + ", ".join(f"{f:.4g}" for f in self.free_free_frequencies_hz[:10]),
        ]
        if self.rigid_body_mass is not None:
            lines.append("  rigid-body mass R^T M R (" + ", ".join(self.directions) + "):")
            for row in self.rigid_body_mass:
                lines.append("    " + " ".join(f"{v:12.5g}" for v in row))
            if self.center_of_gravity is not None:
                lines.append("  centre of gravity [m]: "
                             + ", ".join(f"{v:.5g}" for v in self.center_of_gravity))
            lines.append(f"  grounding: max|K_bb R|/(max|K| max|R|) = "
                         f"{self.rigid_body_stiffness_residual:.2e} "
                         f"({yes(self.rigid_body_stiffness_residual < 1e-6)})")
        else:
            lines.append("  rigid-body mass: not computed (give node coordinates or "
                         "rigid-body vectors)")
        if self.n_modes:
            header = "  mode   f_fixed [Hz]"
            if self.effective_mass_fraction is not None:
                header += "".join(f"  {d:>7s} %" for d in self.directions)
            lines.append(header)
            for j, f in enumerate(self.fixed_base_frequencies_hz):
                row = f"  {j + 1:4d} {f:14.5g}"
                if self.effective_mass_fraction is not None:
                    row += "".join(f"  {100 * v:9.3f}" for v in self.effective_mass_fraction[j])
                lines.append(row)
            if self.effective_mass_fraction is not None:
                lines.append("  total          "
                             + "".join(f"  {100 * v:9.3f}"
                                       for v in self.effective_mass_fraction.sum(axis=0)))
        lines.append(f"  result: {'passed' if self.passed else 'FAILED'}")
        return "\n".join(lines)


def _relative_min_eig(a: np.ndarray) -> float:
    w = np.linalg.eigvalsh(0.5 * (a + a.T))
    return float(w[0] / max(abs(w).max(), 1e-300))


def cb_check(model, stiffness=None, dofs=None, *, coordinates=None, rigid_body=None,
             reference=(0.0, 0.0, 0.0), directions=None) -> CraigBamptonCheck:
    """Check a Craig-Bampton (or any reduced) model before use.

    Boundary DOFs are those not named ``mode.*``; the modal DOFs are the fixed-interface modes.

    Parameters
    ----------
    model : ModalModel or (n, n) array_like
        The reduced model (e.g. from :func:`craig_bampton`), or its mass matrix as read from a
        file, with ``stiffness`` and ``dofs`` (then the symmetry check sees the matrices as
        they are; a :class:`ModalModel` is symmetric by construction).
    stiffness : (n, n) array_like, optional
        Stiffness matrix when ``model`` is a mass matrix.
    dofs : sequence of str, optional
        DOF names when ``model`` is a mass matrix.
    coordinates : mapping node -> (x, y, z), optional
        Node positions [m] for geometric rigid-body motions of boundary DOFs named
        ``<node>.<x|y|z|rx|ry|rz>`` (see :func:`rigid_body_vectors`).
    rigid_body : (n_b, n_rb) array_like, optional
        Rigid-body motions of the boundary DOFs given directly, one column each (instead of
        ``coordinates``). For a feed axis, the one motion along the axis is: 1 at every
        absolute and relative X DOF that moves with the slide, 1/ratio [rad/m] at the motor
        rotor, 0 at the stator and at Y and Z.
    reference : (3,) array_like
        Reference point of the geometric rigid-body motions [m].
    directions : sequence of str, optional
        Labels of the rigid-body columns (default X, Y, Z, RX, RY, RZ for geometric ones).

    Returns
    -------
    CraigBamptonCheck

    Notes
    -----
    Modal effective mass of fixed-interface mode j in rigid-body direction k:
    L_jk^2 / m_jj with L = M_qb R (Craig and Kurdila 2006, sec 18.5); summed over all modes of
    the full model it approaches the rigid-body mass less the part carried statically by the
    boundary. The centre of gravity follows from the coupling terms of the 6x6 rigid-body mass
    about the reference point, e.g. c_x = M[Y, RZ]/M[Y, Y] = -M[Z, RY]/M[Z, Z] (the two
    estimates are averaged), as pyyeti's ``cb.cbcheck`` reports it.
    """
    if isinstance(model, ModalModel):
        if stiffness is not None or dofs is not None:
            raise ValueError("give stiffness and dofs only with a mass matrix, not a ModalModel")
        m, k, names = model.mass, model.stiffness, model.dofs
    else:
        if stiffness is None or dofs is None:
            raise ValueError("with a mass matrix, cb_check needs stiffness and dofs as well")
        m = np.asarray(model.toarray() if scipy.sparse.issparse(model) else model, dtype=float)
        k = np.asarray(stiffness.toarray() if scipy.sparse.issparse(stiffness) else stiffness,
                       dtype=float)
        names = tuple(str(d) for d in dofs)
        if m.ndim != 2 or m.shape[0] != m.shape[1] or m.shape != k.shape \
                or len(names) != m.shape[0]:
            raise ValueError(f"mass {m.shape}, stiffness {k.shape} and {len(names)} DOF names "
                             "do not match")
        if not (np.all(np.isfinite(m)) and np.all(np.isfinite(k))):
            raise ValueError("mass or stiffness has NaN or infinite entries")
    is_mode = np.array([d.startswith("mode.") for d in names])
    b, q = np.flatnonzero(~is_mode), np.flatnonzero(is_mode)
    m_asym = float(np.abs(m - m.T).max() / np.abs(m).max())
    k_asym = float(np.abs(k - k.T).max() / max(np.abs(k).max(), 1e-300))
    m, k = 0.5 * (m + m.T), 0.5 * (k + k.T)
    m_min, k_min = _relative_min_eig(m), _relative_min_eig(k)
    if m_min > 0:
        w2 = scipy.linalg.eigvalsh(k, m)
        free = np.sqrt(np.clip(w2, 0, None)) / RAD_S_PER_HZ
    else:
        free = np.zeros(0)
    if q.size and m_min > 0:
        w2 = scipy.linalg.eigvalsh(k[np.ix_(q, q)], m[np.ix_(q, q)])
        fixed = np.sqrt(np.clip(w2, 0, None)) / RAD_S_PER_HZ
    else:
        fixed = np.zeros(0)

    r = None
    if rigid_body is not None and coordinates is not None:
        raise ValueError("give either coordinates or rigid_body, not both")
    if coordinates is not None:
        covered = {str(k) for k in dict(coordinates)}
        nodes = {str(names[i]).rpartition(".")[0] for i in b
                 if normalise_direction(str(names[i]).rpartition(".")[2]) is not None}
        missing = sorted(nodes - covered)
        if missing and nodes & covered:
            # a rigid-body motion of part of the nodes is no rigid-body motion: its "mass"
            # would count only theirs
            raise ValueError(f"the coordinates cover {len(nodes & covered)} of the "
                             f"{len(nodes)} nodes of the boundary DOFs (missing "
                             f"{missing[:8]}{' ...' if len(missing) > 8 else ''}): the "
                             "rigid-body mass needs every node's position; give coordinates "
                             "of all of them")
        r = rigid_body_vectors([names[i] for i in b], coordinates, reference)
        directions = ("X", "Y", "Z", "RX", "RY", "RZ") if directions is None else directions
        used = np.abs(r).sum(axis=0) > 0
        if not used.any():
            raise ValueError("no boundary DOF is named <node>.<x|y|z|rx|ry|rz> with a node "
                             f"in coordinates; boundary DOFs are {[names[i] for i in b]}")
    elif rigid_body is not None:
        r = np.asarray(rigid_body, dtype=float)
        if r.ndim == 1:
            r = r[:, None]
        if r.shape[0] != b.size or not np.all(np.isfinite(r)):
            raise ValueError(f"rigid_body must have {b.size} finite rows (one per boundary "
                             f"DOF), got shape {r.shape}")
        directions = tuple(f"rb{j + 1}" for j in range(r.shape[1])) if directions is None \
            else directions
    rb_mass = cg = residual = eff = frac = None
    if r is not None:
        directions = tuple(str(d) for d in directions)
        if len(directions) != r.shape[1]:
            raise ValueError(f"{len(directions)} direction labels for {r.shape[1]} motions")
        m_bb, k_bb = m[np.ix_(b, b)], k[np.ix_(b, b)]
        rb_mass = r.T @ m_bb @ r
        residual = float(np.abs(k_bb @ r).max()
                         / max(np.abs(k).max() * np.abs(r).max(), 1e-300))
        if coordinates is not None and np.all(np.diag(rb_mass)[:3] > 0):
            d = np.diag(rb_mass)
            cg = np.array([(rb_mass[1, 5] / d[1] - rb_mass[2, 4] / d[2]) / 2,
                           (rb_mass[2, 3] / d[2] - rb_mass[0, 5] / d[0]) / 2,
                           (rb_mass[0, 4] / d[0] - rb_mass[1, 3] / d[1]) / 2])
        if q.size:
            participation = m[np.ix_(q, b)] @ r
            eff = participation**2 / np.diag(m)[q][:, None]
            with np.errstate(divide="ignore", invalid="ignore"):
                frac = np.where(np.diag(rb_mass) > 0, eff / np.diag(rb_mass), 0.0)
    return CraigBamptonCheck(
        n_boundary=int(b.size), n_modes=int(q.size), mass_asymmetry=m_asym,
        stiffness_asymmetry=k_asym, mass_eigenvalue_ratio=m_min,
        stiffness_eigenvalue_ratio=k_min, mass_positive_definite=bool(m_min > 0),
        stiffness_positive_semidefinite=bool(k_min > -STIFFNESS_RATIO_TOLERANCE),
        free_free_frequencies_hz=free, fixed_base_frequencies_hz=fixed,
        directions=tuple(directions) if r is not None else (), rigid_body_mass=rb_mass,
        center_of_gravity=cg, rigid_body_stiffness_residual=residual, effective_mass=eff,
        effective_mass_fraction=frac)
