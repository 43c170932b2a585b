"""Ports of an FE export named from node numbers and directions.

An FE export names its rows by node and direction (a DOF map with ``node`` and ``dof``
columns, e.g. Ansys' "Matrix Eqn" mapping gives ``12, UX``); servotune's analyses need a few of
them under the names they use: ``pad1.x`` (relative X at a guide-way pad), ``wp.x`` (the
work-piece point), ``motor.rotor``, ``encoder.x``. A *ports file* says which is which, by node
number or by position (the node nearest a point, from a coordinates file ``node,x,y,z``)::

    port,node,direction            port,x,y,z,direction
    pad1.x,1204,UX                 wp.x,0.80,0.50,0.25,x
    motor.rotor,9001,ROTX          pad1.x,0.20,0.15,0.00,x

:func:`name_ports` renames those rows of the DOF list; every other row keeps its
``<node>.<direction>`` name. Directions may be spelt ``x``/``ux``/``tx``/``1`` (translations)
and ``rx``/``rotx``/``4`` (rotations), the Ansys and Nastran (component numbers 1-6) ways.
Positions are in m.

A direction may carry a sign: ``-UX`` (``-x``, ``-ROTX``, Nastran ``-1``; ``+x`` is ``x``) names
a port whose positive direction is opposite to the export's DOF, as where the encoder head's
node is rotated or the motor's rotation is defined against the screw's. The port's coordinate
is then the negative of the export's, q_port = -q_export: :func:`port_signs` gives the sign of
each row and :func:`apply_signs` turns M and K into D M D and D K D, D = diag(+-1) (a
congruence with an orthogonal D: exact, symmetric, the same eigenvalues and definiteness).

Where the guide way is rigid ground in the model (as in a model of the slide alone), the
relative X at a pad is the slide node's X there; with a flexible bed, export the relative
motion as its own DOF (or a coupling element) and name that one.

Every problem is a :class:`PortError` that names the port, what was not found and what to do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse

from ..tablefile import TableFileError, read_table

__all__ = [
    "DIRECTIONS",
    "Port",
    "PortError",
    "apply_signs",
    "name_ports",
    "normalise_direction",
    "normalise_node",
    "port_signs",
    "read_ports",
    "signed_direction",
]

DIRECTIONS = ("x", "y", "z", "rx", "ry", "rz")
_ALIASES = {}
for _i, _d in enumerate(DIRECTIONS):
    _axis = _d[-1]
    if _d.startswith("r"):
        names = (_d, f"rot{_axis}", f"r{_axis}", f"theta{_axis}", f"ur{_axis}", str(_i + 1),
                 f"r{_i - 2}")
    else:
        names = (_d, f"u{_axis}", f"t{_axis}", str(_i + 1), f"t{_i + 1}", f"u{_i + 1}")
    for _name in names:
        _ALIASES[_name] = _d
_SIGNS = {"+": 1, "-": -1}
_DIRECTION_FIX = ("use x, y, z, rx, ry, rz (or UX, ROTX, ..., or the component numbers 1-6), "
                  "with a leading - where the port's positive direction is opposite to the "
                  "export's (e.g. -UX, -ROTX, -1)")


class PortError(TableFileError):
    """A port that cannot be found in the export; the message names the port and the fix."""


def normalise_direction(text) -> str | None:
    """Return the direction ``x``/``y``/``z``/``rx``/``ry``/``rz`` of an export's label, or None.

    Parameters
    ----------
    text : str
        The direction as an export labels it: ``x``, ``UX``, ``rotz``, Nastran ``1``-``6``,
        ``T1``-``R3`` ...

    Returns
    -------
    str or None
        The direction, None when the label is not one.

    Examples
    --------
    >>> [normalise_direction(t) for t in ("UX", "rotz", "3", "T2", "foo")]
    ['x', 'rz', 'z', 'y', None]
    """
    return _ALIASES.get(str(text).strip().lower())


def signed_direction(text) -> tuple[int, str] | None:
    """Return the sign and the direction of a port's direction, or None.

    Parameters
    ----------
    text : str or int
        A direction as :func:`normalise_direction` knows it, optionally with one leading sign:
        ``-UX``, ``+x``, ``-ROTX``, Nastran ``-1``.

    Returns
    -------
    (int, str) or None
        The sign (+1 or -1) and the direction (``x`` ... ``rz``); None when the text (after
        its sign) is not a direction.

    Examples
    --------
    >>> [signed_direction(t) for t in ("-UX", "+rotz", "x", -1, "--x", "-foo")]
    [(-1, 'x'), (1, 'rz'), (1, 'x'), (-1, 'x'), None, None]
    """
    text = str(text).strip()
    sign = _SIGNS.get(text[:1], 0)
    direction = normalise_direction(text[1:] if sign else text)
    return None if direction is None else (sign or 1, direction)


def normalise_node(text) -> str:
    """Return a node id as text.

    Integers lose leading zeros and a ``.0`` tail (``"0012.0"`` -> ``"12"``); other ids are
    stripped.

    Parameters
    ----------
    text : str or int
        The node id as written.

    Returns
    -------
    str
        The normalised id.
    """
    text = str(text).strip()
    try:
        value = float(text)
    except ValueError:
        return text
    if math.isfinite(value) and value == int(value):
        return str(int(value))
    return text


@dataclass(frozen=True)
class Port:
    """One port: a name for the DOF of a node (given by number or by position) in a direction.

    Parameters
    ----------
    name : str
        The DOF name servotune uses (``pad1.x``, ``wp.x``, ``motor.rotor`` ...).
    direction : str
        Any spelling :func:`normalise_direction` knows, optionally with a sign (``-UX``: the
        port's positive direction is opposite to the export's DOF); kept normalised, without
        the sign (``x``).
    node : str or int, optional
        The node number of the export.
    position : (3,) sequence of float, optional
        Instead of ``node``: a point [m]; the nearest node with that direction is taken.
    sign : {1, -1}
        +1 when the port is the export's DOF, -1 when it is its negative; a sign written in
        ``direction`` multiplies it (``Port("encoder.x", "-UX", node=120).sign == -1``).

    Examples
    --------
    >>> p = Port("encoder.x", "-UX", node=120)
    >>> p.direction, p.sign, p.node
    ('x', -1, '120')
    """

    name: str
    direction: str
    node: str | None = None
    position: tuple[float, float, float] | None = None
    sign: int = 1

    def __post_init__(self) -> None:
        name = str(self.name).strip()
        if not name:
            raise PortError("a port needs a name (e.g. pad1.x, wp.x, motor.rotor)")
        if name.startswith("mode."):
            raise PortError(f"port {name!r}: names starting with 'mode.' are reserved for "
                            "modal DOFs")
        signed = signed_direction(self.direction)
        if signed is None:
            raise PortError(f"port {name!r}: unknown direction {self.direction!r}; "
                            f"{_DIRECTION_FIX}")
        if isinstance(self.sign, bool) or self.sign not in (1, -1):
            raise PortError(f"port {name!r}: sign {self.sign!r}; give +1 or -1 (or write the "
                            "sign in the direction, e.g. -UX)")
        sign, direction = signed
        if (self.node is None) == (self.position is None):
            raise PortError(f"port {name!r}: give either a node number or a position x, y, z")
        position = None
        if self.position is not None:
            position = tuple(float(v) for v in self.position)
            if len(position) != 3 or not all(math.isfinite(v) for v in position):
                raise PortError(f"port {name!r}: the position must be 3 finite numbers [m], got "
                                f"{self.position!r}")
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "direction", direction)
        object.__setattr__(self, "node", None if self.node is None else normalise_node(self.node))
        object.__setattr__(self, "position", position)
        object.__setattr__(self, "sign", int(sign * self.sign))


def read_ports(path) -> tuple[Port, ...]:
    """Read ports from a CSV file.

    The columns are ``port``, ``direction`` and either ``node`` or ``x``, ``y``, ``z`` (a row
    may leave ``node`` empty and give the position instead).

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file.

    Returns
    -------
    tuple of Port
        One port per row, in file order.

    Raises
    ------
    PortError
        When the file cannot be read, is empty, lacks a column, or a row has neither a node
        nor a position or names a bad port or direction (the message names file and line).
    """
    table = read_table(path, "ports file", error=PortError,
                       hint="a header row port,node,direction or port,x,y,z,direction, then "
                            "one row per port")
    if not table.has("port", "direction") or not (table.has("node")
                                                  or table.has("x", "y", "z")):
        raise table.error("the ports file needs the columns port, direction and node (or "
                          f"x, y, z); found {sorted(table.header)}")
    ports = []
    for i, row in enumerate(table.records()):
        node = row.get("node") or None
        position = None
        if node is None:
            try:
                position = tuple(float(row[c]) for c in "xyz")
            except (KeyError, ValueError):
                raise table.error(f"port {row.get('port')!r} has neither a node number nor a "
                                  "position x, y, z", i) from None
        try:
            ports.append(Port(row.get("port", ""), row.get("direction", ""), node, position))
        except PortError as exc:
            raise table.error(str(exc), i) from None
    return tuple(ports)


def _split(dof: str):
    node, _, comp = str(dof).rpartition(".")
    return normalise_node(node), normalise_direction(comp)


def name_ports(dofs, ports, coordinates=None, tolerance: float = 1e-3) -> tuple[str, ...]:
    """The DOF names with the ports' rows renamed to the ports' names.

    Parameters
    ----------
    dofs : sequence of str
        DOF names ``<node>.<direction>`` as the DOF map gives them (``12.ux``).
    ports : sequence of Port, or path-like
        The ports (or a ports CSV file, see :func:`read_ports`).
    coordinates : mapping node -> (x, y, z), optional
        Node positions [m] (e.g. from :func:`~servotune.structure.read_coordinates`); needed
        for ports given by position.
    tolerance : float
        Largest distance [m] between a port's position and the node taken for it.

    Returns
    -------
    tuple of str
        The names; a port with a sign (``-UX``) names its row too, :func:`port_signs` gives
        the signs.

    Raises
    ------
    PortError
        A node that is not in the DOF map, a direction the node does not have, a position
        with no node near it, two ports on one DOF or one name twice.

    Examples
    --------
    >>> name_ports(["7.ux", "7.uy", "9.rotx"], [Port("wp.x", "x", node=7),
    ...                                          Port("motor.rotor", "rx", node="9")])
    ('wp.x', '7.uy', 'motor.rotor')
    """
    names = [str(d) for d in dofs]
    for port, row in _port_rows(names, ports, coordinates, tolerance):
        names[row] = port.name
    clash = sorted({n for n in names if names.count(n) > 1})
    if clash:
        raise PortError(f"port names {clash} are also names of other DOFs in the DOF map; "
                        "choose other port names")
    return tuple(names)


def port_signs(dofs, ports, coordinates=None, tolerance: float = 1e-3) -> np.ndarray:
    """The sign of each row: -1 on the rows of ports given with a minus sign, +1 elsewhere.

    Parameters
    ----------
    dofs, ports, coordinates, tolerance
        As :func:`name_ports`.

    Returns
    -------
    numpy.ndarray
        Shape (n,), +1.0 or -1.0 per DOF: the diagonal of D in q_named = D q_export.

    Raises
    ------
    PortError
        As :func:`name_ports`.

    Examples
    --------
    The encoder head's node turned: its UX points against the axis.

    >>> port_signs(["7.ux", "120.ux"], [Port("wp.x", "x", node=7),
    ...                                 Port("encoder.x", "-UX", node=120)]).tolist()
    [1.0, -1.0]
    """
    dofs = [str(d) for d in dofs]
    signs = np.ones(len(dofs))
    for port, row in _port_rows(dofs, ports, coordinates, tolerance):
        signs[row] = float(port.sign)
    return signs


def apply_signs(matrix, signs):
    """Return D A D, D = diag(signs): the matrix in DOFs of which some are reversed.

    Parameters
    ----------
    matrix : (n, n) array_like or scipy sparse matrix
        A mass or stiffness matrix [kg, N/m, ...] in the export's DOFs.
    signs : (n,) array_like
        +1 or -1 per DOF (:func:`port_signs`).

    Returns
    -------
    numpy.ndarray or scipy sparse matrix
        The matrix with the rows and columns of the -1 DOFs multiplied by -1: a dense array,
        or a sparse one of the input's format and kind (never made dense). The input itself
        when every sign is +1.

    Raises
    ------
    ValueError
        When ``signs`` is not n values +1 or -1.

    Notes
    -----
    With q_export = D q (D = D^T = D^-1), the kinetic and strain energies 1/2 q^T D M D q and
    1/2 q^T D K D q give the matrices in the new DOFs: a congruence with an orthogonal D, so
    D M D is symmetric and definite as M is, with the same eigenvalues; multiplying by +-1 is
    exact in floating point.

    Examples
    --------
    >>> apply_signs([[2.0, -1.0], [-1.0, 1.0]], [1, -1]).tolist()
    [[2.0, 1.0], [1.0, 1.0]]
    """
    signs = np.asarray(signs, dtype=float)
    n = signs.size
    if signs.ndim != 1 or not np.all(np.abs(signs) == 1.0):
        raise ValueError(f"signs must be a vector of +1 and -1, got {signs!r}")
    if scipy.sparse.issparse(matrix):
        if matrix.shape != (n, n):
            raise ValueError(f"the matrix is {matrix.shape} but there are {n} signs")
        if np.all(signs > 0):
            return matrix
        coo = matrix.tocoo(copy=True)
        coo.data = coo.data * signs[coo.row] * signs[coo.col]
        return coo.asformat(matrix.format)
    a = np.asarray(matrix)
    if a.shape != (n, n):
        raise ValueError(f"the matrix is {a.shape} but there are {n} signs")
    if np.all(signs > 0):
        return a
    return signs[:, None] * a * signs[None, :]


def _port_rows(dofs: list[str], ports, coordinates, tolerance):
    """(port, row) of each port in the DOF list; raises PortError naming the port."""
    if isinstance(ports, (str, Path)):
        ports = read_ports(ports)
    ports = tuple(ports)
    lookup: dict[tuple[str, str], int] = {}
    by_node: dict[str, list[str]] = {}
    labels: dict[str, list[str]] = {}  # the export's own spelling, for messages
    for row, dof in enumerate(dofs):
        node, direction = _split(dof)
        if direction is None:
            continue
        lookup.setdefault((node, direction), row)
        by_node.setdefault(node, []).append(direction)
        labels.setdefault(node, []).append(dof.rpartition(".")[2])
    coords = None
    if coordinates is not None:
        coords = {normalise_node(k): np.asarray(v, dtype=float)
                  for k, v in dict(coordinates).items()}
    taken: dict[int, str] = {}
    seen = set()
    out = []
    for port in ports:
        if not isinstance(port, Port):
            raise PortError(f"expected Port objects, got {port!r}")
        if port.name in seen:
            raise PortError(f"port {port.name!r} is given twice")
        seen.add(port.name)
        node = port.node if port.node is not None else _nearest(port, by_node, coords,
                                                                 tolerance)
        if node not in by_node:
            sample = ", ".join(sorted(by_node, key=_node_key)[:8])
            raise PortError(f"port {port.name!r}: node {node} is not in the DOF map (it has "
                            f"{len(by_node)} nodes: {sample}{' ...' if len(by_node) > 8 else ''}"
                            "); check the node number against the export")
        row = lookup.get((node, port.direction))
        if row is None:
            raise PortError(f"port {port.name!r}: node {node} has no {port.direction} DOF in "
                            f"the DOF map (it has {', '.join(labels[node])}); choose one of "
                            "those or another node")
        if row in taken:
            raise PortError(f"ports {taken[row]!r} and {port.name!r} are the same DOF "
                            f"({dofs[row]}); give each port its own DOF")
        taken[row] = port.name
        out.append((port, row))
    return out


def _node_key(node: str):
    return (0, int(node), "") if node.isdigit() else (1, 0, node)


def _nearest(port: Port, by_node, coords, tolerance):
    if coords is None:
        raise PortError(f"port {port.name!r} is given by position: give the node coordinates "
                        "too (a CSV file node,x,y,z [m])")
    candidates = [n for n in coords if port.direction in by_node.get(n, ())]
    if not candidates:
        raise PortError(f"port {port.name!r}: no node of the coordinates file has a "
                        f"{port.direction} DOF in the DOF map; check that both files use the "
                        "same node numbers")
    points = np.array([coords[n] for n in candidates])
    dist = np.linalg.norm(points - np.array(port.position), axis=1)
    order = np.argsort(dist)
    best = int(order[0])
    if dist[best] > tolerance:
        raise PortError(
            f"port {port.name!r}: the nearest node with a {port.direction} DOF to "
            f"{port.position} m is {candidates[best]} at {dist[best]:.4g} m, farther than the "
            f"tolerance {tolerance:g} m; check the position and its units (m), or give the "
            "node number")
    if order.size > 1 and dist[int(order[1])] - dist[best] <= 1e-9 * max(tolerance, 1e-300):
        raise PortError(f"port {port.name!r}: nodes {candidates[best]} and "
                        f"{candidates[int(order[1])]} are equally near {port.position}; give "
                        "the node number")
    return candidates[best]
