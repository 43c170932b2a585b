"""A requirement as the tuner sees it, and the registry the requirements join by subclassing.

A requirement is one class on :class:`Requirement`, declared as an entry point of the group
``servotune.requirements`` (:mod:`servotune.plugins`): servotune's own
(:mod:`servotune.tuning.requirements`) in servotune's ``pyproject.toml``, one of another package
in that package's. The NLP (:mod:`servotune.tuning.nlp`), the dense check
(:func:`servotune.tuning.verify.requirement_checks`), the grid exchange and the reports (which
show each :class:`RequirementCheck`'s text) find it through :func:`requirements`, which loads
every declared requirement and checks it (:func:`requirement_problems`). A class defined in the
running program registers itself by being defined (``__init_subclass__``).

A requirement gives:

* **how the NLP imposes it**: rows at every loop frequency (:meth:`Requirement.loop_rows` of
  the velocity and position loops there, each ``>= lower``, named by
  :meth:`Requirement.row_names`), with per-model constants (:attr:`Requirement.gate_size` of
  them, from :meth:`Requirement.gate`: e.g. whether it applies to the model and the edge of
  the band in which it holds), and/or rows in the design variables
  (:meth:`Requirement.design_rows`);
* **how the dense check verifies it**: :meth:`Requirement.model_checks` on the python-control
  analysis of each regime model, or :meth:`Requirement.design_checks` once for the design;
* **how the report shows it**: the text of each check it returns.

Its settings are fields of :class:`servotune.requirements.Requirements` (the ``[requirements]``
of an axis) for servotune's own; a requirement of another package declares its own
(:attr:`Requirement.settings`, each a :class:`servotune.requirements.Setting` with name, unit,
default, range and help): the axis file's ``[requirements]`` accepts and validates them
(:func:`declared_settings`), ``servotune init`` writes them into its template and the report
lists their values; the requirement reads them with :meth:`Requirement.setting`.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass

from ..plugins import (
    REQUIREMENTS_GROUP,
    Plugin,
    PluginError,
    discover,
    load_plugin,
    missing_methods,
)
from ..requirements import Requirements, Setting

__all__ = ["Requirement", "RequirementCheck", "LoopQuantities", "requirements",
           "requirement_problems", "declared_settings", "REQUIREMENTS_PACKAGE",
           "CHECK_TOLERANCE"]

#: servotune's package of requirements, whose modules are imported only in an uninstalled
#: source tree (:func:`servotune.plugins.discover`).
REQUIREMENTS_PACKAGE = "servotune.tuning.requirements"

_REGISTRY: dict[str, type] = {}
#: Requirements loaded from their entry points (and checked), by entry-point name.
_LOADED: dict[str, Plugin] = {}
#: How each loaded requirement is declared, by the requirement's name (for clash messages).
_ORIGIN: dict[str, Plugin] = {}

#: Relative slack of the dense check on a requirement the optimiser imposed exactly (the grid
#: exchange converges to this order; the gates of the hierarchy constraints are soft by a few
#: percent, see :mod:`servotune.tuning.nlp`).
CHECK_TOLERANCE = {"ms": 0.005, "ratio": 0.02}


@dataclass(frozen=True)
class RequirementCheck:
    """One requirement judged on the dense check of one model (or of the axis).

    Parameters
    ----------
    requirement : str
        The requirement (``"stability"``, ``"Ms velocity loop"``, ``"loop hierarchy"``,
        ``"thrust"``, ``"kv_min"``, ...).
    model : str or None
        The regime model's name (the thrust case for ``"thrust"``); None for the axis.
    value, limit : float or None
        The value reached and the limit it is judged against.
    holds : bool
        Whether the requirement holds.
    text : str
        One line for the reader.
    """

    requirement: str
    model: str | None
    value: float | None
    limit: float | None
    holds: bool
    text: str

    def to_dict(self) -> dict:
        """Return the check as JSON-ready data.

        Returns
        -------
        dict
            The fields by name.
        """
        return {"requirement": self.requirement, "model": self.model, "value": self.value,
                "limit": self.limit, "holds": self.holds, "text": self.text}




class LoopQuantities:
    """The symbolic loop quantities at one frequency that loop rows are written in (casadi).

    Attributes
    ----------
    lv, lp : casadi complex pair
        The velocity loop (position loop open) and the position loop (velocity loop closed),
        with ``.re``, ``.im``, ``.abs2()`` and arithmetic (:mod:`servotune.tuning.ports`).
    tv2 : casadi.SX
        ``|T_v|^2 = |L_v|^2 / |1 + L_v|^2``.
    log_omega : casadi.SX
        ``log(omega)`` of the frequency [rad/s].
    kv, ti : casadi.SX
        The design's Kv [1/s] and Ti [s] (symbols when free, numbers when fixed).
    """

    def __init__(self, lv, lp, tv2, log_omega, kv, ti):
        self.lv, self.lp, self.tv2, self.log_omega, self.kv, self.ti = (lv, lp, tv2, log_omega,
                                                                         kv, ti)


class Requirement:
    """Base class of a requirement the tuner imposes and the dense check verifies.

    Subclasses set :attr:`name` (the constraint group's name, unique, as reports and errors
    name it) and :attr:`order` (where its rows and checks come among the others), and implement
    the methods of their kind (see the module docstring). Instances are not made: the methods
    are class methods of the registered class.
    """

    #: Name of the constraint group (rows and checks).
    name: str = ""
    #: Sort key among the registered requirements.
    order: float = 0.0
    #: Loop rows hold as ``row >= lower``.
    lower: float = 0.0
    #: Number of per-model constants :meth:`gate` returns (loop rows only).
    gate_size: int = 0
    #: Whether the rows apply only to the moving models (sliding or viscous pads).
    moving_only: bool = False
    #: The settings it reads from ``[requirements]`` (a requirement of another package; those
    #: of servotune are fields of :class:`servotune.requirements.Requirements`).
    settings: tuple[Setting, ...] = ()

    @classmethod
    def setting(cls, problem, name: str) -> float | None:
        """Return the value of one of :attr:`settings` for a problem: the axis file's, else
        the declared default.

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem (its requirements).
        name : str
            The setting's name.

        Returns
        -------
        float or None
            None when neither the axis nor the declaration gives one.

        Raises
        ------
        KeyError
            The requirement declares no such setting.
        """
        for declared in cls.settings:
            if declared.name == name:
                return problem.requirements.value(declared)
        raise KeyError(f"the requirement {cls.name!r} declares no setting {name!r} (it declares "
                       f"{[d.name for d in cls.settings]})")

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        _complete_docstrings(cls)
        if not cls.name:
            return
        other = _REGISTRY.get(cls.name)
        if other is not None and (other.__module__, other.__qualname__) != (
                cls.__module__, cls.__qualname__):
            origin = _ORIGIN.get(cls.name)
            declared = "" if origin is None else f", the {origin.describe()}"
            raise TypeError(f"a requirement named {cls.name!r} is registered already "
                            f"({other.__module__}.{other.__qualname__}{declared})")
        _REGISTRY[cls.name] = cls

    @classmethod
    def applies(cls, problem) -> bool:
        """Return whether the problem asks for this requirement.

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem (its requirements, drive and models).

        Returns
        -------
        bool
            True when its rows and checks are part of the problem.
        """
        return True

    @classmethod
    def gate(cls, problem, model: int, gamma: float, current_bandwidth) -> tuple[float, ...]:
        """Return the per-model constants of the loop row (``gate_size`` of them).

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem.
        model : int
            Index of the regime model.
        gamma : float
            The model's position-loop bandwidth over Kv.
        current_bandwidth : float or None
            Bandwidth of the current loop [rad/s].

        Returns
        -------
        tuple of float
            The constants, read by :meth:`loop_rows` as ``gate``.
        """
        return ()

    @classmethod
    def row_names(cls, problem) -> tuple[str, ...]:
        """Return the names of the loop rows (none: no rows at the loop frequencies).

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem.

        Returns
        -------
        tuple of str
            One name per row of :meth:`loop_rows`, in its order.
        """
        return ()

    @classmethod
    def loop_rows(cls, problem, q: LoopQuantities, gate) -> list:
        """Return the rows at one loop frequency (each ``>= lower`` when the requirement holds).

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem.
        q : LoopQuantities
            The loops at the frequency.
        gate : list of casadi.SX
            The per-model constants of :meth:`gate`.

        Returns
        -------
        list of casadi.SX
            One row per name of :meth:`row_names`.
        """
        return []

    @classmethod
    def design_rows(cls, problem, value) -> list:
        """Return the rows in the design variables.

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem.
        value : callable
            ``value(name)``: the design variable ``name`` (c, kv, kp, ti) as a casadi
            expression (free) or a number (fixed).

        Returns
        -------
        list of (str, casadi.MX, float, float)
            (row name, expression, lower bound, upper bound) for each row.
        """
        return []

    @classmethod
    def model_checks(cls, problem, design, performance, moving: bool,
                     current_bandwidth) -> list:
        """Return the dense check of the requirement in one (stable) regime model.

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem.
        design : servotune.tuning.Design
            The design.
        performance : servotune.tuning.ModelPerformance
            The python-control analysis of the model.
        moving : bool
            Whether the model's pads move (sliding or viscous).
        current_bandwidth : float or None
            Bandwidth of the current loop [rad/s].

        Returns
        -------
        list of servotune.tuning.RequirementCheck
            One check per judged quantity (none when it does not apply to the model).
        """
        return []

    @classmethod
    def design_checks(cls, problem, design) -> list:
        """Return the check of the requirement on the design itself (no model).

        Parameters
        ----------
        problem : servotune.tuning.TuningProblem
            The problem.
        design : servotune.tuning.Design
            The design.

        Returns
        -------
        list of servotune.tuning.RequirementCheck
            The checks.
        """
        return []


def _complete_docstrings(cls) -> None:
    """Give each method a subclass overrides with a one-paragraph docstring the sections of
    the base method's (its parameters and results are the interface's)."""
    for attr, value in vars(cls).items():
        func = getattr(value, "__func__", value)
        base = getattr(Requirement, attr, None)
        if not callable(func) or base is None or attr.startswith("_"):
            continue
        own = inspect.cleandoc(func.__doc__ or "")
        base_doc = inspect.cleandoc(getattr(base, "__doc__", "") or "")
        if not own or "\n\n" in own.strip() or "\n\n" not in base_doc:
            continue
        func.__doc__ = own + "\n\n" + base_doc.split("\n\n", 1)[1]


def requirement_problems(plugin_class) -> list[str]:
    """Return what a requirement plug-in lacks (empty: usable).

    A requirement is a class on :class:`Requirement` with a ``name``; it imposes something
    (loop rows: :meth:`~Requirement.row_names` and :meth:`~Requirement.loop_rows`, with
    :meth:`~Requirement.gate` when ``gate_size`` > 0; and/or :meth:`~Requirement.design_rows`)
    and checks it (:meth:`~Requirement.model_checks` and/or :meth:`~Requirement.design_checks`):
    a requirement imposed but never checked would pass unverified.

    Parameters
    ----------
    plugin_class : object
        What the entry point loads.

    Returns
    -------
    list of str
        One sentence per thing missing.
    """
    cls = plugin_class
    if not (isinstance(cls, type) and issubclass(cls, Requirement)):
        return [f"it loads {cls!r}, not a class on servotune.tuning.constraint.Requirement"]
    problems = []
    if not (isinstance(cls.name, str) and cls.name):
        problems.append(f"{cls.__qualname__} sets no name (the constraint group's name)")

    def lacks(*names):
        return missing_methods(cls, Requirement, names)

    loop, design = not lacks("loop_rows"), not lacks("design_rows")
    if not (loop or design):
        problems.append(f"{cls.__qualname__} imposes nothing: it implements neither loop_rows "
                        "(with row_names) nor design_rows")
    if loop and lacks("row_names"):
        problems.append(f"{cls.__qualname__} implements loop_rows but not row_names")
    if loop and cls.gate_size and lacks("gate"):
        problems.append(f"{cls.__qualname__} has gate_size = {cls.gate_size} but does not "
                        "implement gate")
    if len(lacks("model_checks", "design_checks")) == 2:
        problems.append(f"{cls.__qualname__} checks nothing: it implements neither "
                        "model_checks nor design_checks")
    settings = getattr(cls, "settings", ())
    if not all(isinstance(x, Setting) for x in settings):
        problems.append(f"{cls.__qualname__}.settings must be a tuple of "
                        "servotune.requirements.Setting")
    else:
        names = [x.name for x in settings]
        builtin = set(Requirements.__dataclass_fields__)
        clash = sorted({n for n in names if names.count(n) > 1} | (set(names) & builtin))
        if clash:
            problems.append(f"{cls.__qualname__} declares the settings {clash} twice or under "
                            "the name of a servotune requirement field; rename them")
    return problems


def _load_all() -> None:
    """Load and check every requirement declared as an entry point (each once)."""
    errors = []
    for name, plugin in discover(REQUIREMENTS_GROUP, REQUIREMENTS_PACKAGE).items():
        if _LOADED.get(name) == plugin:
            continue
        try:
            cls = load_plugin(plugin, requirement_problems)
        except PluginError as exc:
            module = plugin.value.split(":")[0]
            for key in [k for k, v in _REGISTRY.items() if v.__module__ == module]:
                _REGISTRY.pop(key)
            errors.append(str(exc))
            continue
        other = _REGISTRY.get(cls.name)
        if other is not None and (other.__module__, other.__qualname__) != (
                cls.__module__, cls.__qualname__):
            origin = _ORIGIN.get(cls.name)
            declared = ("defined in the running program" if origin is None
                        else f"the {origin.describe()}")
            errors.append(f"two requirements are named {cls.name!r}: "
                          f"{other.__module__}.{other.__qualname__} ({declared}) and "
                          f"{cls.__module__}.{cls.__qualname__} (the {plugin.describe()}); "
                          "uninstall one or rename one")
            continue
        _REGISTRY[cls.name] = cls   # registered when defined, unless emptied since
        _LOADED[name] = plugin
        _ORIGIN[cls.name] = plugin
    if errors:
        raise PluginError("\n".join(errors))


def declared_settings() -> dict[str, tuple[Setting, str]]:
    """Return every setting the registered requirements declare, by name.

    Returns
    -------
    dict of str to (Setting, str)
        Name -> (declaration, the declaring requirement's name).

    Raises
    ------
    servotune.plugins.PluginError
        As :func:`requirements`, or two requirements declaring a setting of one name (both
        named).
    """
    out: dict[str, tuple[Setting, str]] = {}
    for cls in requirements():
        for setting in getattr(cls, "settings", ()):
            if setting.name in out and out[setting.name][1] != cls.name:
                raise PluginError(f"the requirements {out[setting.name][1]!r} and {cls.name!r} "
                                  f"both declare the setting {setting.name!r}; rename one")
            out[setting.name] = (setting, cls.name)
    return out


def requirements(problem=None) -> tuple[type, ...]:
    """Return the registered requirements in their order (those the problem asks for).

    Parameters
    ----------
    problem : servotune.tuning.TuningProblem, optional
        When given, only the requirements that apply to it.

    Returns
    -------
    tuple of type
        :class:`Requirement` subclasses, sorted by ``order``: every entry point of the group
        ``servotune.requirements`` and those defined in the running program.

    Raises
    ------
    servotune.plugins.PluginError
        A declared requirement that cannot be loaded or is refused (all of them named, with
        their entry points and distributions), or two of one name: a tuning without a
        requirement the installation declares would silently be another problem.
    """
    _load_all()
    found = sorted(_REGISTRY.values(), key=lambda c: (c.order, c.name))
    if problem is None:
        return tuple(found)
    return tuple(c for c in found if c.applies(problem))
