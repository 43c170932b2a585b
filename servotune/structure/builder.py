"""Build sparse FE matrices of a machine structure from a physical description.

:class:`StructureBuilder` assembles mass and stiffness matrices from the pieces a feed axis is
made of, with named DOFs: 3D Euler-Bernoulli beams (castings, columns, ball screws), point
masses and rotary inertias (motor rotor, pulleys, work piece), and springs acting on any linear
combination of DOFs (bearings, the ball-screw nut, belt spans, guide-way contact). The result
feeds :func:`servotune.structure.craig_bampton`.

DOF names are ``<node>.<x|y|z|rx|ry|rz>`` for the six DOFs of a node (translations in m,
rotations in rad) plus any scalar DOF added by name (e.g. ``motor.rotor``).

References
----------
J. S. Przemieniecki, Theory of Matrix Structural Analysis, McGraw-Hill (1968), ch 5 and 11
(beam stiffness and consistent mass matrices).
"""

from __future__ import annotations

import itertools

import numpy as np
import scipy.sparse

from ..validation import positive

__all__ = ["NODE_DOFS", "StructureBuilder"]

NODE_DOFS = ("x", "y", "z", "rx", "ry", "rz")


def _beam_local(e, g, area, iy, iz, torsion, rho, length):
    """12x12 local stiffness and consistent mass of a 3D Euler-Bernoulli beam; local DOFs
    (u, v, w, rx, ry, rz) at node 1 then node 2, x along the beam."""
    L = length
    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
    bar = np.array([[1.0, -1.0], [-1.0, 1.0]])
    bar_m = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    for idx, stiff, mass in (([0, 6], e * area / L, rho * area * L),
                             ([3, 9], g * torsion / L, rho * (iy + iz) * L)):
        k[np.ix_(idx, idx)] += stiff * bar
        m[np.ix_(idx, idx)] += mass * bar_m
    kb = np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                   [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]]) / L**3
    mb = np.array([[156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                   [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]]) \
        * (rho * area * L / 420.0)
    flip = np.diag([1.0, -1.0, 1.0, -1.0])  # w-ry plane: ry = -dw/dx
    xy, xz = [1, 5, 7, 11], [2, 4, 8, 10]
    k[np.ix_(xy, xy)] += e * iz * kb
    m[np.ix_(xy, xy)] += mb
    k[np.ix_(xz, xz)] += e * iy * flip @ kb @ flip
    m[np.ix_(xz, xz)] += flip @ mb @ flip
    return k, m


class StructureBuilder:
    """Collects nodes, beams, masses and springs; :meth:`assemble` gives sparse M and K.

    Examples
    --------
    A 200 kg mass on a 2e7 N/m spring to ground rings at sqrt(k/m) = 316.2 rad/s:

    >>> b = StructureBuilder()
    >>> b.add_dof("slide.x")
    >>> b.add_mass("slide.x", 200.0)
    >>> b.add_spring({"slide.x": 1.0}, 2e7)
    >>> M, K, dofs = b.assemble()
    >>> float(np.sqrt(K.toarray()[0, 0] / M.toarray()[0, 0]))
    316.22776601683796
    """

    def __init__(self) -> None:
        self._dofs: dict[str, int] = {}
        self._nodes: dict[str, np.ndarray] = {}
        self._rows: list[np.ndarray] = []
        self._k: list[tuple[np.ndarray, np.ndarray]] = []  # (indices, block)
        self._m: list[tuple[np.ndarray, np.ndarray]] = []

    # -- DOFs and nodes ------------------------------------------------------------------------
    @property
    def dofs(self) -> tuple[str, ...]:
        """DOF names in assembly order."""
        return tuple(self._dofs)

    @property
    def nodes(self) -> dict[str, np.ndarray]:
        """Node positions [m] by name (a copy)."""
        return {k: v.copy() for k, v in self._nodes.items()}

    def add_dof(self, name: str) -> None:
        """Add a scalar DOF (e.g. a rotation ``motor.rotor`` [rad] or a slide translation [m]).

        Parameters
        ----------
        name : str
            The DOF name.

        Raises
        ------
        ValueError
            When the DOF exists already.
        """
        name = str(name)
        if name in self._dofs:
            raise ValueError(f"DOF {name!r} exists already")
        self._dofs[name] = len(self._dofs)

    def add_node(self, name: str, position) -> None:
        """Add a node with six DOFs ``name.x`` ... ``name.rz`` at ``position``.

        Parameters
        ----------
        name : str
            Node name; its DOFs are ``name.x``, ``name.y``, ``name.z`` [m] and ``name.rx``,
            ``name.ry``, ``name.rz`` [rad].
        position : array_like
            Position (x, y, z) [m].

        Raises
        ------
        ValueError
            When the position is not 3 finite numbers, or the node or one of its DOFs exists.
        """
        p = np.asarray(position, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"position of node {name!r} must be 3 finite numbers")
        if name in self._nodes:
            raise ValueError(f"node {name!r} exists already")
        self._nodes[name] = p
        for c in NODE_DOFS:
            self.add_dof(f"{name}.{c}")

    def index(self, name: str) -> int:
        """Return the row of a DOF name.

        Parameters
        ----------
        name : str
            The DOF name.

        Returns
        -------
        int
            Its row (0-based).

        Raises
        ------
        ValueError
            For an unknown DOF.
        """
        try:
            return self._dofs[name]
        except KeyError:
            raise ValueError(f"unknown DOF {name!r}; add its node or DOF first") from None

    def _node_indices(self, node):
        return np.array([self.index(f"{node}.{c}") for c in NODE_DOFS])

    # -- elements ------------------------------------------------------------------------------
    def add_beam(self, node1: str, node2: str, *, e: float, area: float, iy: float, iz: float,
                 torsion: float, rho: float, g: float | None = None, n_elements: int = 1,
                 up=(0.0, 0.0, 1.0), nu: float = 0.3) -> list[str]:
        """Add a straight beam between two nodes, split into ``n_elements`` elements.

        Parameters
        ----------
        node1, node2 : str
            The end nodes (added before with :meth:`add_node`).
        e : float
            Young's modulus [Pa], > 0.
        area, iy, iz, torsion : float
            Cross-section area [m^2] (> 0), second moments about the local y and z axes and the
            torsion constant [m^4] (>= 0). Local x runs from node1 to node2, local y is
            ``up x x`` (normalised), local z = x x y.
        rho : float
            Density [kg/m^3] (consistent mass; rotary inertia of the section in torsion).
        g : float, optional
            Shear modulus [Pa]; default e / (2 (1 + nu)).
        n_elements : int, optional
            Number of elements (default 1); the n_elements - 1 intermediate nodes are added.
        up : array_like, optional
            Direction (x, y, z) that fixes the local y axis (default z; y when the beam runs
            along ``up``).
        nu : float, optional
            Poisson's ratio for the default ``g`` (default 0.3).

        Returns
        -------
        list of str
            All node names along the beam, node1 first (intermediate nodes are named
            ``<node1>-<node2>.<i>``).

        Raises
        ------
        ValueError
            When a section or material value is negative or not finite (e and area also when
            zero), or the beam has zero length.
        KeyError
            When an end node does not exist.
        """
        owner = f"beam {node1}-{node2}:"
        e = positive(owner, "e", e, "Pa")
        area = positive(owner, "area", area, "m^2")
        iy, iz, torsion = (positive(owner, name, v, "m^4", allow_zero=True)
                           for name, v in (("iy", iy), ("iz", iz), ("torsion", torsion)))
        rho = positive(owner, "rho", rho, "kg/m^3", allow_zero=True)
        nu = positive(owner, "nu", nu, allow_zero=True)
        g = e / (2.0 * (1.0 + nu)) if g is None else positive(owner, "g", g, "Pa")
        p1, p2 = self._nodes[node1], self._nodes[node2]
        length = float(np.linalg.norm(p2 - p1))
        if length == 0:
            raise ValueError(f"beam {node1}-{node2} has zero length")
        ex = (p2 - p1) / length
        ey = np.cross(np.asarray(up, float), ex)
        if np.linalg.norm(ey) < 1e-9:
            ey = np.cross(np.array([0.0, 1.0, 0.0]), ex)
        ey /= np.linalg.norm(ey)
        ez = np.cross(ex, ey)
        lam = np.vstack([ex, ey, ez])
        t = np.kron(np.eye(4), lam)
        names = [node1]
        for i in range(1, n_elements):
            name = f"{node1}-{node2}.{i}"
            self.add_node(name, p1 + (p2 - p1) * i / n_elements)
            names.append(name)
        names.append(node2)
        kl, ml = _beam_local(e, g, area, iy, iz, torsion, rho, length / n_elements)
        kg, mg = t.T @ kl @ t, t.T @ ml @ t
        for a, b in itertools.pairwise(names):
            idx = np.concatenate([self._node_indices(a), self._node_indices(b)])
            self._k.append((idx, kg))
            self._m.append((idx, mg))
        return names

    def add_mass(self, dof_or_node: str, mass: float, inertia=None) -> None:
        """Add a point mass on a scalar DOF, or on a node's translations.

        Parameters
        ----------
        dof_or_node : str
            A DOF name (the mass goes on that DOF alone) or a node name (on its x, y, z).
        mass : float
            The mass [kg] (for a rotation DOF its inertia [kg m^2]), >= 0.
        inertia : array_like, optional
            Rotary inertia (Jxx, Jyy, Jzz) [kg m^2] on a node's rotations.

        Raises
        ------
        ValueError
            When the mass or an inertia is negative or not finite, ``inertia`` is given for a
            DOF rather than a node, or the DOF is unknown.
        """
        mass = positive(f"mass at {dof_or_node!r}:", "mass", mass, "kg (kg m^2 on a rotation)",
                        allow_zero=True)
        if dof_or_node in self._nodes:
            diag = np.concatenate([[mass] * 3, np.zeros(3) if inertia is None
                                   else np.asarray(inertia, dtype=float)])
            if diag.shape != (6,) or np.any(diag < 0) or not np.all(np.isfinite(diag)):
                raise ValueError(f"inertia at {dof_or_node!r} must be 3 numbers >= 0")
            self._m.append((self._node_indices(dof_or_node), np.diag(diag)))
        else:
            if inertia is not None:
                raise ValueError("inertia is only for nodes; give a rotation DOF its inertia "
                                 "as its mass")
            self._m.append((np.array([self.index(dof_or_node)]), np.array([[float(mass)]])))

    def add_spring(self, terms: dict, stiffness: float) -> None:
        """A spring on a linear combination of DOFs: energy k (sum_i c_i u_i)^2 / 2.

        ``terms`` maps DOF names to coefficients c_i. ``{"a.x": 1}`` is a spring to ground,
        ``{"a.x": 1, "b.x": -1}`` a spring between two DOFs, and
        ``{"nut.x": 1, "screw.x": -1, "screw.rx": -p}`` a ball-screw nut of lead 2 pi p.

        Parameters
        ----------
        terms : dict
            DOF name -> coefficient c_i [-] (for a rotation DOF, the lever [m]).
        stiffness : float
            Spring stiffness k [N/m], >= 0.

        Raises
        ------
        ValueError
            When the stiffness is negative or not finite, or a DOF is unknown.
        """
        stiffness = positive(f"spring on {sorted(terms)}:", "stiffness", stiffness,
                             "N/m (N m/rad)", allow_zero=True)
        idx = np.array([self.index(n) for n in terms])
        c = np.array([float(v) for v in terms.values()])
        self._k.append((idx, stiffness * np.outer(c, c)))

    def add_rigid_link(self, master: str, slave: str, stiffness: float,
                       rotational_stiffness: float | None = None) -> None:
        """Add a stiff connection making node ``slave`` follow node ``master`` as a rigid offset.

        Three penalty springs of ``stiffness`` on the translations and three of
        ``rotational_stiffness`` on the rotations; used to attach a point (a pad, an encoder
        head) to a beam node.

        Parameters
        ----------
        master : str
            The node followed.
        slave : str
            The node that follows, at its offset from ``master``.
        stiffness : float
            Penalty stiffness of the translations [N/m].
        rotational_stiffness : float, optional
            Penalty stiffness of the rotations [N m/rad]; default ``stiffness`` times 1 m^2.

        Raises
        ------
        KeyError
            When a node does not exist.
        ValueError
            When a stiffness is negative or not finite.
        """
        krot = stiffness if rotational_stiffness is None else rotational_stiffness
        r = self._nodes[slave] - self._nodes[master]
        for axis, comp in enumerate(("x", "y", "z")):
            e = np.eye(3)[axis]
            rot = np.cross(r, e)  # e . (theta x r)
            terms = {f"{slave}.{comp}": 1.0, f"{master}.{comp}": -1.0}
            for j, rc in enumerate(("rx", "ry", "rz")):
                if rot[j] != 0:
                    terms[f"{master}.{rc}"] = -rot[j]
            self.add_spring(terms, stiffness)
            self.add_spring({f"{slave}.r{comp}": 1.0, f"{master}.r{comp}": -1.0}, krot)

    # -- assembly ------------------------------------------------------------------------------
    def assemble(self):
        """Assemble the sparse (CSR) mass and stiffness matrices.

        Returns
        -------
        mass : scipy.sparse.csr_array
            The mass matrix [kg, kg m^2], (n, n).
        stiffness : scipy.sparse.csr_array
            The stiffness matrix [N/m, N m/rad], (n, n).
        dofs : tuple of str
            The n DOF names, in assembly order.
        """
        n = len(self._dofs)

        def build(blocks):
            rows, cols, vals = [], [], []
            for idx, block in blocks:
                r, c = np.meshgrid(idx, idx, indexing="ij")
                rows.append(r.ravel())
                cols.append(c.ravel())
                vals.append(block.ravel())
            if not rows:
                return scipy.sparse.csr_array((n, n))
            a = scipy.sparse.coo_array((np.concatenate(vals),
                                        (np.concatenate(rows), np.concatenate(cols))),
                                       shape=(n, n)).tocsr()
            a.sum_duplicates()
            return a

        return build(self._m), build(self._k), self.dofs
