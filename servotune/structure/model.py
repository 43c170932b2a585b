"""The reduced structural model: mass, stiffness and damping over named degrees of freedom.

A :class:`ModalModel` is what a Craig-Bampton reduction (or a hand-built lumped model) hands to
the rest of servotune: symmetric mass and stiffness matrices whose rows are named DOFs. Boundary
(physical) DOFs carry names such as ``pad1.x`` (relative X translation at a guide-way pad),
``wp.x``/``wp.y``/``wp.z`` (work-piece point), ``motor.rotor``/``motor.stator`` (rotations);
fixed-interface modal DOFs are named ``mode.1``, ``mode.2``, ... Translations are in m, rotations
in rad; generalised forces in N and N m.

Distributed damping is modal: a damping ratio per mode of the model as given (3 % on every mode
in the paper, sec 3), turned once into a physical damping matrix

    D = M Phi diag(2 zeta_i omega_i) Phi^T M,        Phi^T M Phi = I,

so that rigid-body modes (omega = 0) stay undamped and the same matrix serves every
configuration: when DOFs are locked (guide-way pads stuck), rows and columns of M, K and D are
removed, and the modes of the locked model are damped by the physical D, not re-assigned 3 %.
This keeps the linear analyses and the nonlinear simulation (where stiction holds the pads) on
one and the same structure. :meth:`ModalModel.with_damping` re-assigns modal damping on the
current configuration when that is wanted instead.

References
----------
R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses", AIAA Journal 6
(1968) 1313-1319.
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 3 (41-DOF reduced model, 3 % modal damping).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control
import numpy as np
import scipy.linalg

from ..validation import positive

__all__ = ["ModalModel", "ReductionInfo", "UnknownDofError", "signal_name"]

SYMMETRY_TOLERANCE = 1e-8  # relative to the largest entry


class UnknownDofError(KeyError, ValueError):
    """A DOF name that the model does not have (the message lists the known names)."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0])


def signal_name(dof: str, prefix: str = "") -> str:
    """Return the python-control signal name of a DOF.

    python-control reserves '.' for ``subsystem.signal``: ``signal_name("wp.x")`` is
    ``"wp_x"``, with ``prefix="f_"`` it is ``"f_wp_x"``.

    Parameters
    ----------
    dof : str
        DOF name.
    prefix : str, optional
        Prefix of the signal (``"f_"`` for a force input, ``"v_"`` for a velocity output).

    Returns
    -------
    str
        The prefix and the DOF name with every '.' replaced by '_'.
    """
    return prefix + dof.replace(".", "_")


def _check_matrix(name: str, a, n: int | None = None) -> np.ndarray:
    a = np.array(a, dtype=float)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {a.shape}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} is {a.shape[0]}x{a.shape[0]} but the model has {n} DOFs")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} has NaN or infinite entries")
    scale = np.abs(a).max() if a.size else 0.0
    asym = np.abs(a - a.T).max() if a.size else 0.0
    if asym > SYMMETRY_TOLERANCE * scale:
        raise ValueError(f"{name} is not symmetric: max |A - A^T| = {asym:.3g} is more than "
                         f"{SYMMETRY_TOLERANCE:g} of max |A| = {scale:.3g}; check the export")
    return 0.5 * (a + a.T)


def _read_only(a: np.ndarray) -> np.ndarray:
    """A C-contiguous copy of ``a`` that refuses in-place changes."""
    a = np.array(a, dtype=float, order="C")
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class ReductionInfo:
    """How a model was reduced by Craig-Bampton: what its fixed-interface modes cover.

    Attributes
    ----------
    n_full, n_boundary : int
        DOFs of the full FE model and boundary DOFs kept as physical coordinates.
    fixed_interface_hz : tuple of float
        Frequencies of the kept fixed-interface modes [Hz], ascending.
    next_hz : float
        The first fixed-interface mode not kept [Hz]: ``inf`` when every one is kept, ``nan``
        when it is not known.
    complete_below_hz : float
        Every fixed-interface mode below this frequency is kept [Hz] (verified by a dense
        solution or a Sturm count; ``inf`` when all are kept).
    method : str
        How the fixed-interface modes were computed: "dense", "lanczos" (with a Sturm
        check), "lanczos-unchecked" or "none".
    restarts : int
        Deflated Lanczos restarts the Sturm check asked for.
    """

    n_full: int
    n_boundary: int
    fixed_interface_hz: tuple[float, ...]
    next_hz: float = math.nan
    complete_below_hz: float = math.nan
    method: str = "unknown"
    restarts: int = 0

    def __post_init__(self) -> None:
        f = tuple(float(x) for x in self.fixed_interface_hz)
        if any(not math.isfinite(x) or x < 0 for x in f):
            raise ValueError("fixed_interface_hz must hold finite frequencies >= 0")
        if int(self.n_boundary) < 0 or int(self.n_full) < int(self.n_boundary) + len(f):
            raise ValueError(f"inconsistent sizes: {self.n_full} DOFs, {self.n_boundary} "
                             f"boundary DOFs and {len(f)} modes")
        object.__setattr__(self, "fixed_interface_hz", f)
        object.__setattr__(self, "n_full", int(self.n_full))
        object.__setattr__(self, "n_boundary", int(self.n_boundary))

    @property
    def reached_hz(self) -> float:
        """Frequency of the highest kept fixed-interface mode [Hz] (0 with none kept)."""
        return self.fixed_interface_hz[-1] if self.fixed_interface_hz else 0.0

    def to_dict(self) -> dict:
        """Plain values for JSON (``None`` for an unknown or unbounded frequency).

        Returns
        -------
        dict
            JSON-ready values (SI; str, numbers, lists, None).
        """
        def finite(x):
            return float(x) if math.isfinite(x) else None

        return {"n_full": self.n_full, "n_boundary": self.n_boundary,
                "n_modes": len(self.fixed_interface_hz),
                "fixed_interface_hz": list(self.fixed_interface_hz),
                "next_hz": finite(self.next_hz), "all_kept": self.next_hz == math.inf,
                "complete_below_hz": finite(self.complete_below_hz),
                "method": self.method, "restarts": self.restarts}


@dataclass(frozen=True, eq=False)
class ModalModel:
    """Reduced structural model with named DOFs and modal damping.

    Parameters
    ----------
    mass : (n, n) array_like
        Symmetric positive definite mass matrix [kg, kg m^2, ...].
    stiffness : (n, n) array_like
        Symmetric positive semi-definite stiffness matrix [N/m, N m/rad, ...].
    dofs : sequence of str
        Unique DOF names, one per row.
    damping_ratio : float or (n,) array_like
        Modal damping ratio zeta [-] of each mode of this model (ascending frequency), or one
        value for all. Default 0.03 (the paper, sec 3).
    damping : (n, n) array_like, optional
        A physical damping matrix [N s/m, ...] to use instead of ``damping_ratio``.
    reduction : ReductionInfo, optional
        For a Craig-Bampton model, what its fixed-interface modes cover (set by
        :func:`~servotune.structure.craig_bampton`; kept by :meth:`locked`,
        :meth:`with_damping` and :meth:`with_added`).

    Raises
    ------
    ValueError
        Non-square, mismatched, non-symmetric or non-finite matrices; a mass matrix that is not
        positive definite; a stiffness matrix with a negative eigenvalue; duplicate DOF names;
        damping ratios outside [0, 1).

    Notes
    -----
    The model keeps read-only copies of its matrices (``mass``, ``stiffness``, ``damping``,
    ``damping_ratio``), so that its modes, computed once, always belong to them: an in-place
    change such as ``model.stiffness[0, 0] = 1.0`` raises ``ValueError``. Vary a model with
    ``dataclasses.replace``: ``replace(model, stiffness=k)`` keeps the physical damping matrix
    of ``model``; ``replace(model, stiffness=k, damping=None)`` re-assigns its modal damping
    ratios to the new modes (as :meth:`with_damping` does).

    Examples
    --------
    A 1000 kg slide on a 4e7 N/m spring rings at sqrt(k/m):

    >>> model = ModalModel([[1000.0]], [[4e7]], ["slide.x"])
    >>> float(model.natural_frequencies()[0])
    200.0
    >>> import dataclasses
    >>> float(dataclasses.replace(model, stiffness=[[9e7]]).natural_frequencies()[0])
    300.0
    """

    mass: np.ndarray
    stiffness: np.ndarray
    dofs: tuple[str, ...]
    damping_ratio: float | np.ndarray = 0.03
    damping: np.ndarray | None = None
    reduction: ReductionInfo | None = field(default=None, kw_only=True)
    _modes: tuple = field(init=False, repr=False, compare=False)
    _ports: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        dofs = tuple(str(d) for d in self.dofs)
        if len(set(dofs)) != len(dofs):
            dup = sorted({d for d in dofs if dofs.count(d) > 1})
            raise ValueError(f"ModalModel.dofs has duplicate DOF names {dup}; name each DOF once")
        n = len(dofs)
        if n == 0:
            raise ValueError("ModalModel.dofs is empty: a model needs at least one DOF")
        m = _check_matrix("mass", self.mass, n)
        k = _check_matrix("stiffness", self.stiffness, n)
        try:
            np.linalg.cholesky(m)
        except np.linalg.LinAlgError:
            low = float(np.linalg.eigvalsh(m)[0])
            raise ValueError(f"mass matrix is not positive definite (smallest eigenvalue "
                             f"{low:.3g}); every DOF needs mass or must be removed") from None
        omega2, phi = scipy.linalg.eigh(k, m)
        scale = max(abs(omega2).max(), 1e-300)
        if omega2[0] < -1e-9 * scale:
            raise ValueError(f"stiffness matrix is indefinite (eigenvalue {omega2[0]:.3g}); "
                             "check signs and constraints of the export")
        omega = np.sqrt(np.clip(omega2, 0.0, None))
        omega[omega2 < 1e-12 * scale] = 0.0  # rigid-body modes
        if self.damping is not None:
            d = _check_matrix("damping", self.damping, n)
            if np.linalg.eigvalsh(d)[0] < -1e-9 * max(np.abs(d).max(), 1e-300):
                raise ValueError("damping matrix is indefinite: it would inject energy")
            zeta = np.full(n, np.nan)
        else:
            given = np.asarray(self.damping_ratio, dtype=float)
            if given.ndim > 1 or (given.ndim == 1 and given.size not in (1, n)):
                raise ValueError(f"ModalModel.damping_ratio has {given.size} values for {n} "
                                 f"modes; give one ratio for every mode, or one per mode "
                                 f"({n} values, lowest mode first)")
            zeta = np.broadcast_to(given, (n,)).copy()
            if not np.all(np.isfinite(zeta)) or np.any(zeta < 0.0) or np.any(zeta >= 1.0):
                raise ValueError(f"ModalModel.damping_ratio must lie in [0, 1), got "
                                 f"{self.damping_ratio!r}; give one ratio, or one per mode")
            mphi = m @ phi
            d = mphi @ np.diag(2.0 * zeta * omega) @ mphi.T
            d = 0.5 * (d + d.T)
        if self.reduction is not None and not isinstance(self.reduction, ReductionInfo):
            raise ValueError("ModalModel.reduction must be a ReductionInfo or None, got "
                             f"{type(self.reduction).__name__}")
        # private read-only copies: the cached modes below stay those of these matrices
        object.__setattr__(self, "mass", _read_only(m))
        object.__setattr__(self, "stiffness", _read_only(k))
        object.__setattr__(self, "dofs", dofs)
        object.__setattr__(self, "damping_ratio",  # the ratios given, None for a matrix
                           _read_only(zeta) if self.damping is None else None)
        object.__setattr__(self, "damping", _read_only(d))
        object.__setattr__(self, "_modes", (_read_only(omega), _read_only(phi)))
        object.__setattr__(self, "_ports", {})

    # -- names ---------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of DOFs."""
        return len(self.dofs)

    def index(self, names) -> np.ndarray:
        """Return the row indices of DOF names (a str gives a 0-d array).

        Parameters
        ----------
        names : str or sequence of str
            DOF names.

        Returns
        -------
        numpy.ndarray of int
            Their rows (0-based); 0-d for a str.

        Raises
        ------
        UnknownDofError
            For a name the model does not have; the message lists the known names.
        """
        lookup = {d: i for i, d in enumerate(self.dofs)}
        single = isinstance(names, str)
        out = []
        for name in [names] if single else names:
            if name not in lookup:
                physical = [d for d in self.dofs if not d.startswith("mode.")]
                raise UnknownDofError(
                    f"unknown DOF {name!r}; the model has {physical}"
                    + (f" and {self.n - len(physical)} modal DOFs 'mode.1'..." if
                       len(physical) < self.n else ""))
            out.append(lookup[name])
        return np.array(out[0] if single else out, dtype=int)

    # -- modes ---------------------------------------------------------------------------
    def natural_frequencies(self) -> np.ndarray:
        """Return the undamped natural angular frequencies [rad/s], ascending (rigid-body: 0).

        Returns
        -------
        numpy.ndarray
            omega_j [rad/s], shape (n,).
        """
        return self._modes[0].copy()

    def mode_shapes(self) -> np.ndarray:
        """Return the mass-normalised mode shapes as columns, Phi^T M Phi = I.

        Returns
        -------
        numpy.ndarray
            Phi, shape (n, n), one column per mode in the order of :meth:`natural_frequencies`.
        """
        return self._modes[1].copy()

    def modal_damping_ratios(self) -> np.ndarray:
        """Return the damping ratio of each undamped mode from the physical damping matrix.

        The diagonal of Phi^T D Phi over 2 omega; NaN for rigid-body modes.

        Returns
        -------
        numpy.ndarray
            One ratio [-] per mode, in the order of :meth:`natural_frequencies`.
        """
        omega, phi = self._modes
        diag = np.einsum("ij,ik,kj->j", phi, self.damping, phi)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(omega > 0, diag / (2.0 * omega), np.nan)

    # -- derived models --------------------------------------------------------------------
    def locked(self, names) -> ModalModel:
        """Return the model with these DOFs held at zero (e.g. guide-way pads stuck).

        Rows and columns are removed from M, K and the physical damping matrix D.

        Parameters
        ----------
        names : sequence of str
            The DOFs held.

        Returns
        -------
        ModalModel
            The model without those DOFs; its :meth:`port_receptance` goes through this model's.

        Raises
        ------
        UnknownDofError
            For a DOF the model does not have.
        ValueError
            When every DOF would be held.

        Examples
        --------
        Locking one end of a two-mass chain leaves the other mass on its spring:

        >>> chain = ModalModel([[1.0, 0], [0, 4.0]], [[1e4, -1e4], [-1e4, 1e4]], ["a", "b"])
        >>> float(chain.locked(["a"]).natural_frequencies()[0])
        50.0
        """
        drop = set(self.index([names] if isinstance(names, str) else list(names)).tolist())
        keep = np.array([i for i in range(self.n) if i not in drop], dtype=int)
        if keep.size == 0:
            raise ValueError("cannot lock every DOF of the model")
        sub = np.ix_(keep, keep)
        held = ModalModel(self.mass[sub], self.stiffness[sub], [self.dofs[i] for i in keep],
                          damping=self.damping[sub], reduction=self.reduction)
        held._ports["base"] = ("locked", self, [self.dofs[i] for i in sorted(drop)])
        return held

    def with_damping(self, damping_ratio) -> ModalModel:
        """Return the same M and K with modal damping re-assigned on this configuration's modes.

        Parameters
        ----------
        damping_ratio : float or array_like
            One modal damping ratio [-], or one per mode.

        Returns
        -------
        ModalModel
            The model with the damping D of those ratios.
        """
        return ModalModel(self.mass, self.stiffness, self.dofs, damping_ratio=damping_ratio,
                          reduction=self.reduction)

    def with_added(self, stiffness=None, damping=None) -> ModalModel:
        """Return the model with extra physical stiffness and/or damping.

        For example the contact springs and dampers at the pads.

        Parameters
        ----------
        stiffness : array_like or dict, optional
            Added stiffness [N/m]: an (n, n) symmetric matrix, or ``{dof: k}`` for grounded
            springs on single DOFs (each finite and >= 0).
        damping : array_like or dict, optional
            Added viscous damping [N s/m], in the same two forms.

        Returns
        -------
        ModalModel
            The same mass, the stiffness and damping with the additions (the damping is then
            physical, no longer modal); its :meth:`port_receptance` goes through this model's
            when the additions touch at most a quarter of the DOFs.

        Raises
        ------
        ValueError
            When a grounded value is negative or not finite, or a matrix is not a symmetric,
            finite (n, n) matrix.
        UnknownDofError
            When a DOF of a dict is not in the model.
        """
        k = self.stiffness.copy()
        d = self.damping.copy()
        for target, extra, what, unit in ((k, stiffness, "stiffness", "N/m"),
                                          (d, damping, "damping", "N s/m")):
            if extra is None:
                continue
            if isinstance(extra, dict):
                for name, value in extra.items():
                    value = positive("ModalModel.with_added", f"{what}[{name!r}]", value, unit,
                                     allow_zero=True)
                    i = int(self.index(name))
                    target[i, i] += value
            else:
                target += _check_matrix("added matrix", extra, self.n)
        new = ModalModel(self.mass, k, self.dofs, damping=d, reduction=self.reduction)
        # the added elements live on a few DOFs S: port_receptance goes through the parent
        dk, dd = k - self.stiffness, d - self.damping
        touched = np.flatnonzero((np.abs(dk).sum(axis=0) + np.abs(dd).sum(axis=0)) > 0)
        if 0 < touched.size <= max(self.n // 4, 1):
            sub = np.ix_(touched, touched)
            new._ports["base"] = ("added", self, [self.dofs[i] for i in touched], dk[sub],
                                  dd[sub])
        return new

    # -- systems ---------------------------------------------------------------------------
    def to_state_space(self, inputs=None, outputs=None, velocity_outputs=(),
                       name: str = "structure") -> control.StateSpace:
        """Second-order model as a python-control ``StateSpace`` with named signals.

        States are the displacements then the velocities of all DOFs. Inputs are generalised
        forces at the DOFs in ``inputs``; outputs are displacements of ``outputs`` followed by
        velocities of ``velocity_outputs``. Both default to all DOFs that are not modal.
        Signal names follow :func:`signal_name`: for DOF ``wp.x`` the force input is ``f_wp_x``,
        the displacement output ``wp_x`` and the velocity output ``v_wp_x``.

        Parameters
        ----------
        inputs : sequence of str, optional
            DOFs the force inputs [N] act on (default: the DOFs that are not ``mode.*``, or
            all when every DOF is modal).
        outputs : sequence of str, optional
            DOFs whose displacements [m] are outputs (same default).
        velocity_outputs : sequence of str, optional
            DOFs whose velocities [m/s] are further outputs (default none).
        name : str, optional
            Name of the system (default "structure"); states ``x_<dof>`` then ``v_<dof>``.

        Returns
        -------
        control.StateSpace
            2 n states, the named inputs and outputs, D = 0.

        Raises
        ------
        UnknownDofError
            When a DOF is not in the model.

        Examples
        --------
        The static compliance of a spring-mass is 1/k:

        >>> sys = ModalModel([[2.0]], [[8.0]], ["x"]).to_state_space()
        >>> round(float(sys.dcgain()), 12)
        0.125
        """
        physical = [d for d in self.dofs if not d.startswith("mode.")] or list(self.dofs)
        inputs = physical if inputs is None else list(inputs)
        outputs = physical if outputs is None else list(outputs)
        velocity_outputs = list(velocity_outputs)
        n = self.n
        minv_k = np.linalg.solve(self.mass, self.stiffness)
        minv_d = np.linalg.solve(self.mass, self.damping)
        a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv_k, -minv_d]])
        sel_in = np.zeros((n, len(inputs)))
        sel_in[self.index(inputs), np.arange(len(inputs))] = 1.0
        b = np.vstack([np.zeros((n, len(inputs))), np.linalg.solve(self.mass, sel_in)])
        c = np.zeros((len(outputs) + len(velocity_outputs), 2 * n))
        c[np.arange(len(outputs)), self.index(outputs)] = 1.0
        c[len(outputs) + np.arange(len(velocity_outputs)), n + self.index(velocity_outputs)] = 1.0
        return control.ss(
            a, b, c, np.zeros((c.shape[0], b.shape[1])), name=name,
            inputs=[signal_name(d, "f_") for d in inputs],
            outputs=[signal_name(d) for d in outputs]
            + [signal_name(d, "v_") for d in velocity_outputs],
            states=[signal_name(d, "x_") for d in self.dofs]
            + [signal_name(d, "v_") for d in self.dofs])

    def receptance(self, omega, inputs, outputs) -> np.ndarray:
        """Displacement per force X/F(j omega) between named DOFs by direct solution.

        Solves (K - w^2 M + j w D) X = F at every frequency (a cost of n^3 per frequency;
        :meth:`port_receptance` gives the same from the modes at a cost linear in the number
        of modes, the way to go for models of more than a few dozen DOFs).

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s].
        inputs : sequence of str
            DOFs the unit forces act on.
        outputs : sequence of str
            DOFs whose displacements are returned.

        Returns
        -------
        numpy.ndarray of complex
            Shape (len(omega), len(outputs), len(inputs)) [m/N, or rad/(N m) and the mixed
            units for rotation DOFs].

        Raises
        ------
        UnknownDofError
            When a DOF is not in the model.
        numpy.linalg.LinAlgError
            When the dynamic stiffness is singular at a frequency (omega = 0 with rigid-body
            modes).
        """
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        i_in, i_out = self.index(list(inputs)), self.index(list(outputs))
        rhs = np.zeros((self.n, len(i_in)))
        rhs[i_in, np.arange(len(i_in))] = 1.0
        out = np.empty((omega.size, len(i_out), len(i_in)), dtype=complex)
        for j, w in enumerate(omega):
            dyn = self.stiffness - w * w * self.mass + 1j * w * self.damping
            out[j] = np.linalg.solve(dyn, rhs)[i_out]
        return out

    def _modal_damping_diagonal(self):
        """diag(Phi^T D Phi) when the damping is diagonal in the modes (to 1e-9), else None
        (cached)."""
        if "modal_d" not in self._ports:
            phi = self._modes[1]
            dm = phi.T @ self.damping @ phi
            off = dm - np.diag(np.diag(dm))
            scale = max(float(np.abs(dm).max(initial=0.0)), 1e-300)
            diagonal = float(np.abs(off).max(initial=0.0)) <= 1e-9 * scale
            self._ports["modal_d"] = np.diag(dm).copy() if diagonal else None
        return self._ports["modal_d"]

    def port_receptance(self, omega, inputs, outputs) -> np.ndarray:
        """Return the receptance X/F(j omega) between named DOFs through the modes and the ports.

        The cost per frequency is linear in the number of modes.

        Parameters
        ----------
        omega : array_like
            Angular frequencies [rad/s].
        inputs : sequence of str
            DOFs the unit forces act on.
        outputs : sequence of str
            DOFs whose displacements are returned.

        Returns
        -------
        numpy.ndarray of complex
            Same result and shape as :meth:`receptance`, (len(omega), len(outputs),
            len(inputs)).

        Raises
        ------
        UnknownDofError
            When a DOF is not in the model.
        ValueError
            At omega = 0 for a model with modal damping and rigid-body modes (the receptance
            is infinite).

        Notes
        -----
        With modal damping (mass-normalised modes Phi, Phi^T D Phi = diag(2 zeta_j omega_j))
        it is the modal sum ``H = Phi_out diag(1 / (omega_j^2 - w^2 + 2 j zeta_j omega_j w))
        Phi_in^T``. A model derived from one with modal damping by :meth:`locked` or
        :meth:`with_added` (whose physical damping is then no longer diagonal in its own modes)
        is evaluated through the parent's receptance at the few DOFs concerned, S:

        * DOFs held: ``H = H_oi - H_oS H_SS^-1 H_Si`` (the reactions that keep u_S = 0);
        * elements added on S, Delta(w) = dK_SS + j w dD_SS (Woodbury's identity):
          ``H = H_oi - H_oS (I + Delta H_SS)^-1 Delta H_Si``;

        an |S| x |S| solve per frequency. Any other non-modal damping falls back to
        :meth:`receptance`.

        Examples
        --------
        The driving point of a damped spring-mass, 1 / (k - m w^2 + j c w) = 1 / (6 + 0.4 j):

        >>> model = ModalModel([[2.0]], [[8.0]], ["x"], damping=[[0.4]])
        >>> h = complex(model.port_receptance([1.0], ["x"], ["x"])[0, 0, 0])
        >>> bool(abs(h - 1 / (6 + 0.4j)) < 1e-15)
        True
        """
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        inputs, outputs = list(inputs), list(outputs)
        i_in, i_out = self.index(inputs), self.index(outputs)
        d = self._modal_damping_diagonal()
        if d is not None:
            wr, phi = self._modes
            p_out, p_in = phi[i_out], phi[i_in]
            out = np.empty((omega.size, len(i_out), len(i_in)), dtype=complex)
            chunk = max(1, 4_000_000 // max(self.n, 1))
            for a in range(0, omega.size, chunk):
                w = omega[a:a + chunk]
                den = wr[None, :] ** 2 - w[:, None] ** 2 + 1j * w[:, None] * d[None, :]
                if np.any(den == 0):
                    raise ValueError("the receptance is infinite at omega = 0 for a model with "
                                     "rigid-body modes")
                out[a:a + chunk] = np.einsum("oj,fj,ij->foi", p_out, 1.0 / den, p_in)
            return out
        base = self._ports.get("base")
        if base is None:
            return self.receptance(omega, inputs, outputs)
        kind, parent, s_dofs = base[:3]
        n_o, n_i, n_s = len(outputs), len(inputs), len(s_dofs)
        h = parent.port_receptance(omega, inputs + s_dofs, outputs + s_dofs)
        h_oi, h_os = h[:, :n_o, :n_i], h[:, :n_o, n_i:]
        h_si, h_ss = h[:, n_o:, :n_i], h[:, n_o:, n_i:]
        if kind == "locked":
            return h_oi - h_os @ np.linalg.solve(h_ss, h_si)
        dk, dd = base[3], base[4]
        delta = dk[None] + 1j * omega[:, None, None] * dd[None]
        return h_oi - h_os @ np.linalg.solve(np.eye(n_s) + delta @ h_ss, delta @ h_si)

    # -- participation -----------------------------------------------------------------------
    def modal_compliance(self, dof: str) -> np.ndarray:
        """Return the static compliance each mode contributes at a DOF.

        phi_j(dof)^2 / omega_j^2 [m/N] (0 for rigid-body modes), in the order of
        :meth:`natural_frequencies`.

        Summed over the modes it is the static driving-point compliance of a model without
        rigid-body modes (modal expansion of K^-1).

        Parameters
        ----------
        dof : str
            The DOF.

        Returns
        -------
        numpy.ndarray
            phi_j(dof)^2 / omega_j^2 [m/N] per mode.

        Raises
        ------
        UnknownDofError
            For a DOF the model does not have.
        """
        omega, phi = self._modes
        row = phi[int(self.index(dof))]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(omega > 0, row**2 / np.where(omega > 0, omega, 1.0) ** 2, 0.0)

    def participation(self, dof: str) -> np.ndarray:
        """Return the share of each mode in the motion of a DOF.

        Its part of the static compliance there, phi_j(dof)^2 / omega_j^2 over the sum of all
        flexible modes (rigid-body modes get 0).

        Parameters
        ----------
        dof : str
            The DOF.

        Returns
        -------
        numpy.ndarray
            The share [-] of each mode, summing to 1 (all 0 when no flexible mode moves the DOF).

        Raises
        ------
        UnknownDofError
            For a DOF the model does not have.

        Examples
        --------
        A heavy tip mass on two springs in series with a light mass between them: the low mode
        (the tip swinging on both springs) carries nearly all the static compliance at the tip:

        >>> chain = ModalModel([[1.0, 0], [0, 100.0]], [[2e6, -1e6], [-1e6, 1e6]], ["a", "b"])
        >>> share = chain.participation("b")
        >>> bool(share[0] > 0.99 and abs(share.sum() - 1) < 1e-12)
        True
        """
        c = self.modal_compliance(dof)
        total = c.sum()
        return c / total if total > 0 else c

    def compliance_peak(self, dof: str, omega_min: float, omega_max: float,
                        n: int = 2000) -> tuple[float, float]:
        """Return the largest driving-point receptance magnitude |X/F| at a DOF in a band.

        From a logarithmic grid of ``n`` points refined by a bounded scalar search around the
        best point.

        Parameters
        ----------
        dof : str
            The DOF (force and displacement).
        omega_min, omega_max : float
            The band [rad/s], ``0 < omega_min < omega_max``.
        n : int, optional
            Points of the logarithmic grid (default 2000).

        Returns
        -------
        omega_peak : float
            Frequency of the peak [rad/s].
        peak : float
            The peak |X/F| [m/N].

        Raises
        ------
        ValueError
            When the band is not ``0 < omega_min < omega_max``.
        UnknownDofError
            When the DOF is not in the model.
        """
        from scipy.optimize import minimize_scalar

        if not 0 < omega_min < omega_max:
            raise ValueError(f"need 0 < omega_min < omega_max, got {omega_min}, {omega_max}")
        grid = np.geomspace(omega_min, omega_max, n)
        mag = np.abs(self.port_receptance(grid, [dof], [dof])[:, 0, 0])
        j = int(np.argmax(mag))
        lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, n - 1)]
        res = minimize_scalar(lambda w: -abs(self.port_receptance([w], [dof], [dof])[0, 0, 0]),
                              bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-9 * hi})
        if -res.fun > mag[j]:
            return float(res.x), float(-res.fun)
        return float(grid[j]), float(mag[j])
