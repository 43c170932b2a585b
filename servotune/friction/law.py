"""The interface of a guide-way friction law, and the registry the laws join by subclassing it.

A friction law is one class on :class:`FrictionLaw`, declared as an entry point of the group
``servotune.friction_laws`` (:mod:`servotune.plugins`) named after its :attr:`~FrictionLaw.name`:
servotune's own laws (:mod:`servotune.friction.laws`) in servotune's ``pyproject.toml``, a law of
another package in that package's. The axis description (``[friction.<name>]``), the linear
contacts of the plant (:mod:`servotune.plant`), the command line and the time simulation
(:mod:`servotune.simulate`, whose compiled kernel is built for the law's remainder) find it
through :func:`friction_law` and :func:`friction_law_names`. The names come from the installed
metadata; a law's module is imported when the law is first asked for, and the class is checked
then (:data:`REQUIRED_METHODS`, :data:`REQUIRED_NONLINEAR_METHODS`). A class defined in the
running program (a script, a test) registers itself by being defined (``__init_subclass__``)
and is found by name too.

What a law gives (values are axis totals, shared equally by the guide-way pads):

* **linear contacts for the plant**: :meth:`~FrictionLaw.presliding` (the contact at rest,
  spring and damper), :meth:`~FrictionLaw.sliding_system` (linearised about steady sliding at a
  speed) and :meth:`~FrictionLaw.describing_function` (Ceq, Keq at a vibration; by default the
  first harmonic of :meth:`~FrictionLaw.periodic_force`);
* **the design job** (``servotune tune``, the verdict, the thrust budget):
  :meth:`~FrictionLaw.with_viscous` (the law with the design's viscous damping C in place of
  its own viscous part), :meth:`~FrictionLaw.steady_force` and
  :meth:`~FrictionLaw.steady_slope` (the sliding friction at constant speed and its slope; by
  default from :meth:`~FrictionLaw.periodic_force` under a constant velocity, the law's own
  steady state, and its central difference);
* **the time simulation**: a linear block per pad (:meth:`~FrictionLaw.pad_block`) and, for a
  nonlinear law, a numba-compiled remainder ``(component, v, z, p) -> (r, dr_dv, dr_dz)``
  (:meth:`~FrictionLaw.remainder`) with its parameters, the states each remainder reads, the
  stored elastic energy and the scales of the integrator's error control;
* **harmonic balance**: :meth:`~FrictionLaw.periodic_force`, the force of one pad on the law's
  periodic orbit under a periodic pad velocity;
* **the axis file**: :meth:`~FrictionLaw.from_table` reads ``[friction.<name>]``.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 3 (friction lumped at the guide-way pads), Eq 3, Eq 8-10.
A. Gelb, W. E. Vander Velde, Multiple-Input Describing Functions and Nonlinear System Design,
McGraw-Hill (1968), ch 2 (the describing function as the first harmonic of the periodic
response), Eq 2.3-7.
"""

from __future__ import annotations

import math

import control
import numpy as np

from ..plugins import (
    FRICTION_LAWS_GROUP,
    Plugin,
    PluginError,
    discover,
    load_plugin,
    missing_methods,
)
from ..structure.model import signal_name

__all__ = ["FrictionLaw", "friction_law", "friction_law_names", "friction_laws",
           "LAWS_PACKAGE", "REQUIRED_METHODS", "REQUIRED_NONLINEAR_METHODS"]

#: servotune's package of laws, whose modules are imported only in an uninstalled source tree
#: (:func:`servotune.plugins.discover`).
LAWS_PACKAGE = "servotune.friction.laws"

#: What every law implements: the axis file, the linear contact at rest, the time simulation's
#: linear block, the force, and the law with another viscous part (the design's C).
REQUIRED_METHODS = ("from_table", "presliding", "pad_block", "friction_force", "with_viscous")
#: What a nonlinear law (``nonlinear = True``) implements besides: the time simulation's
#: remainder and harmonic balance.
REQUIRED_NONLINEAR_METHODS = ("remainder", "remainder_parameters", "remainder_states",
                              "error_scales", "newton_tolerance", "periodic_force")

_REGISTRY: dict[str, type] = {}
#: Laws loaded from their entry points (and checked), by name: how each is declared.
_LOADED: dict[str, Plugin] = {}


class FrictionLaw:
    """Base class of a guide-way friction law (registered by defining a subclass).

    A subclass sets the class attribute :attr:`name` (lower case, the key of
    ``[friction.<name>]`` in an axis description) and implements at least
    :meth:`from_table`, :meth:`presliding`, :meth:`pad_block`, :meth:`friction_force` and, for a
    nonlinear law (``nonlinear = True``), :meth:`remainder`, :meth:`remainder_parameters`,
    :meth:`remainder_states`, :meth:`error_scales`, :meth:`newton_tolerance` and
    :meth:`periodic_force` (and :meth:`spring_states` when it has elastic states); a law loaded
    from its entry point that lacks one is refused. A class with ``name = None`` (an
    intermediate base) is not registered.

    Signals of :meth:`pad_block`: inputs the pad velocity ``v_<pad>``, the remainders
    (:meth:`remainder_signals`) and the constant ``one``; outputs the force on the pad DOF
    ``f_<pad>`` (minus the friction force), the friction force ``F_<pad>`` and, for a nonlinear
    law, its states (recorded by the simulation).

    See Also
    --------
    friction_law, friction_law_names
    servotune.simulate.simulate : integrates the law at every pad
    servotune.plant.Contact : the linear contacts built from :meth:`presliding`,
        :meth:`sliding_system` and :meth:`describing_function`
    """

    #: Registry key (``[friction.<name>]``); None for an abstract base.
    name: str | None = None
    #: Whether the law has a nonlinear remainder for the time simulation.
    nonlinear: bool = False
    #: Prefixes of the remainder inputs of one pad, one per remainder component.
    remainder_prefixes: tuple[str, ...] = ("r_",)
    #: How to fix a bad ``[friction.<name>]`` (shown with the error).
    table_hint: str = "give the law's parameters in SI units (see its documentation)"

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        name = cls.__dict__.get("name")
        if name is None:
            return
        if not (isinstance(name, str) and name.isidentifier() and name == name.lower()):
            raise TypeError(f"{cls.__qualname__}.name must be a lower-case identifier (the key "
                            f"of [friction.<name>] in an axis file), got {name!r}")
        known = _REGISTRY.get(name)
        if known is not None and (known.__module__, known.__qualname__) != (
                cls.__module__, cls.__qualname__):
            origin = _LOADED.get(name)
            declared = "" if origin is None else f" (the {origin.describe()})"
            raise TypeError(f"two friction laws are named {name!r}: "
                            f"{known.__module__}.{known.__qualname__}{declared} and "
                            f"{cls.__module__}.{cls.__qualname__}; rename one")
        _REGISTRY[name] = cls

    # ---------------------------------------------------------------- the axis file

    @classmethod
    def from_table(cls, value) -> FrictionLaw:
        """Build the law from its entry ``[friction.<name>]`` of an axis description.

        Parameters
        ----------
        value : dict or str
            The table of parameters (SI) or the name of a published set.

        Returns
        -------
        FrictionLaw
            The law, axis totals.

        Raises
        ------
        ValueError
            A parameter is missing, unknown or out of range (the message names it).
        """
        raise ValueError(f"the {cls.name!r} friction law cannot be read from an axis file")

    # ---------------------------------------------------------------- linear contacts

    @property
    def viscous_part(self) -> float:
        """The viscous part of the law [N s/m] (axis total): the damping of the paper's
        viscous-only model unless the axis gives one."""
        return 0.0

    def with_viscous(self, c: float) -> FrictionLaw:
        """Return the law with the viscous part ``c`` in place of its own (axis total).

        The design job tunes the guide ways' viscous damping C: every regime model, the
        verdict's simulations and harmonic balance and the thrust budget take the law with its
        viscous part replaced by the design's C (for LuGre: sigma2 = C).

        Parameters
        ----------
        c : float
            Viscous damping [N s/m], >= 0.

        Returns
        -------
        FrictionLaw
            A law of the same kind whose :attr:`viscous_part` is ``c``.
        """
        raise NotImplementedError

    def steady_force(self, speed: float) -> float:
        """Return the friction at constant sliding speed, axis total, viscous part included.

        The default is the law's own steady state: :meth:`periodic_force` under a constant
        velocity (the periodic orbit of a constant velocity is the steady state), averaged
        over the samples. A law with a closed form overrides it.

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s], finite and non-zero.

        Returns
        -------
        float
            F_ss(v) [N], of the sign of v.

        Raises
        ------
        ValueError
            If ``speed`` is zero or not finite, or the law has no :meth:`periodic_force` to
            take it from.
        """
        speed = _sliding_speed(speed)
        velocity = np.full(64, speed)
        try:
            # a travel of 1 m per period: far beyond any presliding range, so the states settle
            force = self.periodic_force(velocity, 1.0 / abs(speed))
        except NotImplementedError:
            raise ValueError(f"the {self.name!r} friction law gives neither steady_force nor "
                             "periodic_force: the thrust budget and the feeding regimes need "
                             "one of them (implement it in the law)") from None
        return float(np.mean(force))

    def steady_slope(self, speed: float) -> float:
        """Return the slope dF_ss/dv of the steady sliding friction [N s/m], viscous part
        included: negative where the friction falls with speed (the Stribeck region).

        The default is the central difference of :meth:`steady_force` over 1e-3 of the speed.

        Parameters
        ----------
        speed : float
            Sliding speed v [m/s], finite and non-zero.

        Returns
        -------
        float
            The slope [N s/m].
        """
        speed = _sliding_speed(speed)
        h = 1e-3 * abs(speed)
        return float((self.steady_force(speed + h) - self.steady_force(speed - h)) / (2 * h))

    def to_dict(self) -> dict:
        """Return the law as JSON-ready data: its name and parameters (SI).

        Returns
        -------
        dict
            ``law`` and, when the law keeps its parameters in a ``params`` object with a
            ``to_dict``, those parameters.
        """
        out = {"law": self.name}
        params = getattr(self, "params", None)
        if hasattr(params, "to_dict"):
            out.update(params.to_dict())
        return out

    def presliding(self) -> tuple[float, float]:
        """Return the contact linearised at rest (all of it sticking), axis totals.

        Returns
        -------
        (stiffness, damping) : tuple of float
            Spring [N/m] and damper [N s/m] of the presliding contact.
        """
        raise NotImplementedError

    def sliding_system(self, speed: float) -> control.StateSpace:
        """Return the contact linearised about steady sliding at a speed, axis total.

        The default is the linearisation of the law's own simulation model: its linear block
        (:meth:`pad_block` at ``speed``, one pad carrying the whole law) with each remainder
        (:meth:`remainder`) replaced by its tangent at the steady state, which is found by
        integrating the block at the constant speed (``scipy.integrate.solve_ivp``, BDF) and
        polished by Newton steps. A law with a closed form overrides it.

        Parameters
        ----------
        speed : float
            Sliding speed v0 [m/s], non-zero.

        Returns
        -------
        control.StateSpace
            SISO, from the velocity deviation [m/s] to the force deviation [N].

        Raises
        ------
        ValueError
            If ``speed`` is 0 or not finite, or the law's model has no steady state at it.
        """
        speed = _sliding_speed(speed)
        pad = "x"
        block = self.pad_block(pad, 1, speed)
        inputs, outputs = list(block.input_labels), list(block.output_labels)
        a, b = np.asarray(block.A, float), np.asarray(block.B, float)
        c, d = np.asarray(block.C, float), np.asarray(block.D, float)
        iv, jf = inputs.index(signal_name(pad, "v_")), outputs.index(signal_name(pad, "F_"))
        remainders = [inputs.index(r) for r in self.remainder_signals(pad)]
        one = inputs.index("one") if "one" in inputs else None
        nr, nx = len(remainders), a.shape[0]
        states = list(block.state_labels)
        reads = [states.index(z) for z in self.remainder_states(pad)[:nr]] if nr else []
        select = np.zeros((nr, nx))
        select[np.arange(nr), reads] = 1.0
        kernel = self.remainder() if nr else None
        params = np.asarray(self.remainder_parameters(speed), float) if nr else None
        constant = b[:, iv] * speed + (b[:, one] if one is not None else 0.0)

        def rem(x):
            out = np.array([kernel(k, speed, float(x[reads[k]]), params) for k in range(nr)],
                           dtype=float).reshape(nr, 3)
            return out[:, 0], out[:, 1], out[:, 2]

        def rate(x):
            return a @ x + constant + (b[:, remainders] @ rem(x)[0] if nr else 0.0)

        def jacobian(x):
            return a + (b[:, remainders] @ (rem(x)[2][:, None] * select) if nr else 0.0)

        x = np.zeros(nx)
        if nx:
            from scipy.integrate import solve_ivp

            _, scales = self.error_scales() if nr else (None, (1.0,))
            horizon = 200.0 * max(scales) / abs(speed)
            run = solve_ivp(lambda _t, y: rate(y), (0.0, horizon), x, method="BDF",
                            jac=lambda _t, y: jacobian(y), rtol=1e-10,
                            atol=1e-12 * max(scales))
            x = run.y[:, -1]
            for _ in range(20):
                step = np.linalg.solve(jacobian(x), rate(x))
                x = x - step
                if np.all(np.abs(step) <= 1e-14 * max(scales)):
                    break
            if not np.all(np.isfinite(x)) or np.max(np.abs(rate(x))) > 1e-9 * abs(speed):
                raise ValueError(f"the {self.name!r} friction law's model has no steady state "
                                 f"at {speed!r} m/s")
        if nr:
            _, dr_dv, dr_dz = rem(x)
        else:
            dr_dv = dr_dz = np.zeros(0)
        br, dr = b[:, remainders], d[jf, remainders]
        return control.ss(jacobian(x) if nx else np.zeros((0, 0)),
                          (b[:, iv] + br @ dr_dv).reshape(nx, 1),
                          (c[jf] + dr @ (dr_dz[:, None] * select)).reshape(1, nx),
                          [[float(d[jf, iv] + dr @ dr_dv)]], inputs=["velocity"],
                          outputs=["force"], name=f"{self.name}_sliding")

    def describing_function(self, amplitude: float, omega: float,
                            n_samples: int = 512) -> tuple[float, float]:
        """Equivalent damping Ceq [N s/m] and stiffness Keq [N/m] (axis totals) under
        ``x = A sin(omega t)``: the first harmonic of the periodic force.

        Parameters
        ----------
        amplitude : float
            Displacement amplitude A [m], > 0.
        omega : float
            Angular frequency [rad/s], > 0.
        n_samples : int
            Samples of the period given to :meth:`periodic_force`.

        Returns
        -------
        (ceq, keq) : tuple of float
            ``F_1 = (Keq + j omega Ceq) X_1`` for the first harmonics F_1, X_1 of force and
            displacement (Gelb and Vander Velde 1968, Eq 2.3-7).

        Raises
        ------
        ValueError
            If amplitude or omega is not positive and finite.
        NotImplementedError
            If the law has no :meth:`periodic_force`.
        """
        amplitude, omega = float(amplitude), float(omega)
        if not (amplitude > 0 and omega > 0 and math.isfinite(amplitude * omega)):
            raise ValueError(f"the describing function needs amplitude > 0 m and omega > 0 "
                             f"rad/s, got {amplitude!r} and {omega!r}")
        theta = 2.0 * math.pi * np.arange(n_samples) / n_samples
        force = self.periodic_force(amplitude * omega * np.cos(theta), 2.0 * math.pi / omega)
        # x = A sin(theta) has X_1 = -j A; F_1 = (2/N) sum F e^{-j theta}
        f1 = 2.0 / n_samples * np.sum(force * np.exp(-1j * theta))
        ratio = f1 / (-1j * amplitude)
        return float(ratio.imag / omega), float(ratio.real)

    # ---------------------------------------------------------------- time simulation

    @property
    def n_remainders(self) -> int:
        """Remainder inputs per pad (0 for a linear law)."""
        return len(self.remainder_prefixes) if self.nonlinear else 0

    def remainder_signals(self, pad: str) -> tuple[str, ...]:
        """Return the names of the remainder inputs of one pad, one per component.

        Parameters
        ----------
        pad : str
            The pad DOF.

        Returns
        -------
        tuple of str
            ``<prefix><pad>`` for each of :attr:`remainder_prefixes`.
        """
        return tuple(signal_name(pad, prefix) for prefix in self.remainder_prefixes[
            :self.n_remainders])

    def remainder_states(self, pad: str) -> tuple[str, ...]:
        """Return the state of :meth:`pad_block` each remainder component reads (its ``z``).

        Parameters
        ----------
        pad : str
            The pad DOF.

        Returns
        -------
        tuple of str
            One state name per remainder component.
        """
        raise NotImplementedError

    def spring_states(self, pad: str, n_pads: int) -> tuple[tuple[str, float], ...]:
        """Return one pad's elastic states with their stiffnesses (stored energy ``sum k z^2 / 2``).

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the law.

        Returns
        -------
        tuple of (str, float)
            (state name, stiffness [N/m]) pairs; empty for a law without elastic states.
        """
        return ()

    def pad_block(self, pad: str, n_pads: int, speed: float = 0.0) -> control.StateSpace:
        """Return the linear part of the law for one pad.

        Parameters
        ----------
        pad : str
            The pad DOF.
        n_pads : int
            The number of pads sharing the axis-total law equally.
        speed : float
            Operating speed [m/s] of the linearisation (0: at rest).

        Returns
        -------
        control.StateSpace
            Inputs ``v_<pad>``, the remainders and ``one``; outputs ``f_<pad>``, ``F_<pad>`` and the
            law's states (see the class docstring).
        """
        raise NotImplementedError

    def remainder(self):
        """Return the compiled remainder ``(component, v, z, p) -> (r, dr_dv, dr_dz)``.

        A module-level numba function of the law's module (in servotune,
        :func:`servotune.cache.cached_njit`, which keeps its compiled code in the user's cache;
        in another package, ``numba.njit(cache=True)`` keeps it beside that package's
        module): the simulation compiles its kernel around it
        (:func:`servotune.simulate.integrator.chunk_kernel`).

        Returns
        -------
        numba dispatcher
            The remainder [m/s] and its partial derivatives in v [-] and z [1/s].
        """
        raise NotImplementedError

    def remainder_parameters(self, speed: float = 0.0) -> np.ndarray:
        """Return the parameter vector ``p`` of :meth:`remainder` for a linearisation.

        Parameters
        ----------
        speed : float
            Operating speed [m/s] of the linear part (0: at rest).

        Returns
        -------
        numpy.ndarray
            The parameters, in the order the remainder reads them.
        """
        raise NotImplementedError

    def error_scales(self) -> tuple[float, tuple[float, ...]]:
        """Return the scales of the integrator's local error control.

        Returns
        -------
        (v_scale, z_scales) : tuple
            Velocity scale [m/s] and one state scale [m] per remainder component: errors in the
            pad motion are measured relative to them.
        """
        raise NotImplementedError

    def newton_tolerance(self, step: float) -> float:
        """Return the tolerance on the remainders in the Newton iteration of a step.

        Parameters
        ----------
        step : float
            The integration step [s].

        Returns
        -------
        float
            Tolerance [m/s].
        """
        raise NotImplementedError

    def friction_force(self, v, z):
        """Return the friction force, axis total, at a velocity and state.

        Parameters
        ----------
        v : array_like
            Pad velocity [m/s].
        z : array_like
            The law's state [m].

        Returns
        -------
        numpy.ndarray
            Friction force [N].
        """
        raise NotImplementedError

    # ---------------------------------------------------------------- harmonic balance

    def periodic_force(self, velocity, period: float, share: float = 1.0) -> np.ndarray:
        """Friction force [N] of one pad carrying ``share`` of the law, on the periodic orbit.

        Parameters
        ----------
        velocity : array_like
            The pad velocity [m/s] at N equally spaced instants of one period (periodic: the
            sample after the last is the first).
        period : float
            The period [s], > 0.
        share : float
            The pad's share of the axis-total law (``1 / n_pads``), > 0.

        Returns
        -------
        numpy.ndarray
            The force [N] at the same N instants, with the law's states on their periodic orbit.
        """
        raise NotImplementedError(f"the {self.name!r} friction law has no periodic force")


def _sliding_speed(speed) -> float:
    speed = float(speed)
    if not (math.isfinite(speed) and speed != 0.0):
        raise ValueError(f"the steady sliding friction needs a finite, non-zero speed [m/s], got "
                         f"{speed!r}")
    return speed


def _plugins() -> dict:
    """The laws' entry points by name (servotune's package imported in an uninstalled tree)."""
    return discover(FRICTION_LAWS_GROUP, LAWS_PACKAGE)


def _check_law(name: str):
    """The check of a law loaded from the entry point ``name``: what it lacks."""

    def check(cls) -> list[str]:
        if not (isinstance(cls, type) and issubclass(cls, FrictionLaw)):
            return [f"it loads {cls!r}, not a class on servotune.friction.law.FrictionLaw"]
        problems = []
        if cls.__dict__.get("name") != name:
            problems.append(f"its class {cls.__module__}.{cls.__qualname__} is named "
                            f"{cls.__dict__.get('name')!r}, not {name!r} (the entry point's "
                            "name is the law's name)")
        required = REQUIRED_METHODS + (REQUIRED_NONLINEAR_METHODS if cls.nonlinear else ())
        missing = missing_methods(cls, FrictionLaw, required)
        if missing:
            kind = "a nonlinear law" if cls.nonlinear else "every law"
            problems.append(f"{cls.__qualname__} does not implement {', '.join(missing)} "
                            f"(required of {kind}: {', '.join(required)})")
        return problems

    return check


def _load(name: str, plugins: dict) -> None:
    """Load and check the law of entry point ``name`` unless done already."""
    plugin = plugins[name]
    if _LOADED.get(name) == plugin and name in _REGISTRY:
        return
    try:
        cls = load_plugin(plugin, _check_law(name))
    except PluginError:
        # a refused class registered itself when defined: it must not be found by name
        for key in [k for k, v in _REGISTRY.items() if v.__module__ == plugin.value.split(":")[0]]:
            _REGISTRY.pop(key)
        raise
    _REGISTRY[name] = cls   # registered when defined, unless the registry was emptied since
    _LOADED[name] = plugin


def friction_laws() -> dict[str, type]:
    """Return all friction laws, by name, each loaded from its entry point and checked.

    Returns
    -------
    dict of str to type
        Name -> class on :class:`FrictionLaw`.

    Raises
    ------
    servotune.plugins.PluginError
        A law that cannot be loaded or is refused (the message names every one, with its
        entry point and distribution), or two laws of one name.

    Examples
    --------
    >>> {"lugre", "viscous"} <= set(friction_laws())
    True
    """
    plugins = _plugins()
    errors = []
    for name in plugins:
        try:
            _load(name, plugins)
        except PluginError as exc:
            errors.append(str(exc))
    if errors:
        raise PluginError("\n".join(errors))
    return dict(_REGISTRY)


def friction_law_names() -> tuple[str, ...]:
    """Return the names of the friction laws, sorted (none is imported to list them).

    Returns
    -------
    tuple of str
        The names (keys of ``[friction.<name>]``): the entry points of the group
        ``servotune.friction_laws`` and the laws defined in the running program.

    Raises
    ------
    servotune.plugins.PluginError
        Two laws of one name (the message names both entry points and their distributions).
    """
    return tuple(sorted(set(_plugins()) | set(_REGISTRY)))


def friction_law(name: str) -> type:
    """Return the friction law class registered under a name.

    Parameters
    ----------
    name : str
        The law's name (case-insensitive), e.g. ``"lugre"`` or ``"gms"``.

    Returns
    -------
    type
        The class on :class:`FrictionLaw` (loaded from its entry point and checked on first
        use).

    Raises
    ------
    ValueError
        For an unknown name (the message lists the known ones).
    servotune.plugins.PluginError
        The law's plug-in cannot be loaded or is refused, or two plug-ins share the name
        (the message names the entry point, its distribution and what is wrong).

    See Also
    --------
    friction_law_names, friction_laws

    Examples
    --------
    >>> friction_law("lugre").__name__
    'LuGreFriction'
    """
    key = str(name).lower()
    plugins = _plugins()
    if key in plugins:
        _load(key, plugins)
    try:
        return _REGISTRY[key]
    except KeyError:
        raise ValueError(f"unknown friction law {name!r}; the known laws are "
                         f"{sorted(set(plugins) | set(_REGISTRY))} (a law of another package "
                         f"is found once that package is installed with an entry point in "
                         f"the group {FRICTION_LAWS_GROUP!r})") from None
