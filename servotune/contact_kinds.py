"""The kinds of linear guide-way contact, registered, and how each is built from a friction law.

A contact kind (:class:`ContactKind`) names a linear model of the guide-way friction for the plant
(:class:`servotune.plant.Contact`), the parameters it takes and how it is built from the axis'
friction (:class:`servotune.friction.guideway.GuideWayFriction`, whose law is any registered
:class:`servotune.friction.law.FrictionLaw`). The plant, the frequency responses, the analyses and
the command line (``--contact``) take the kinds from here (:func:`contact_kinds`); a new kind is
one :func:`register_contact_kind`. This module imports nothing numerical, so that the command
line can list the kinds without loading numpy.

References
----------
G. Bianchi et al., "Analysis of vibration damping in machine tools", Procedia CIRP 21 (2014),
sec 3, 4.1, 4.2 (the contact models), Eq 8-10 (describing function).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from types import MappingProxyType

__all__ = ["CONTACT_PARAMETERS", "ContactKind", "ContactParameter", "contact_kind",
           "contact_kinds", "register_contact_kind"]


@dataclass(frozen=True)
class ContactParameter:
    """A parameter a contact kind can take (as :func:`servotune.analysis.axis_contact` and the
    command line name it).

    Parameters
    ----------
    name : str
        Keyword of :func:`servotune.analysis.axis_contact` and of :meth:`ContactKind.build`.
    flag : str
        Command-line option.
    unit : str
        SI unit, for messages.
    what : str
        What it sets, for messages ("the sliding speed").
    nonzero : bool
        Whether 0 counts as not given.
    """

    name: str
    flag: str
    unit: str
    what: str
    nonzero: bool = False


#: The parameters of the contact kinds, by name.
CONTACT_PARAMETERS = MappingProxyType({p.name: p for p in (
    ContactParameter("c", "--c", "N s/m", "the viscous damping"),
    ContactParameter("amplitude", "--amplitude", "m", "the vibration"),
    ContactParameter("frequency_hz", "--frequency-hz", "Hz", "the vibration"),
    ContactParameter("speed", "--speed", "m/s", "the sliding speed", nonzero=True),
)})


@dataclass(frozen=True)
class ContactKind:
    """A kind of linear guide-way contact: how it is built from the axis' friction law.

    Parameters
    ----------
    name : str
        The kind (``Contact.kind``, ``--contact``).
    summary : str
        One line for help texts.
    build : callable or None
        ``build(friction, **parameters) -> Contact`` with ``friction`` a
        :class:`GuideWayFriction` (None for kinds that need no friction) and the parameters of
        :data:`CONTACT_PARAMETERS` it uses (the others None); None for the kinds servotune
        builds itself (:func:`servotune.plant.build_contact`), so that this module imports
        nothing of the plant.
    required, optional : tuple of str
        The parameters it needs and those it may take.
    purpose : str
        What the required parameters describe (for messages).
    example : str
        The command-line options of an example (for messages).
    pads : {"contact", "locked", "free"}
        Whether the contact acts at the pads, holds them rigidly, or is absent.
    needs_friction : bool
        Whether it is built from the axis' friction law.

    Raises
    ------
    ValueError
        A required or optional parameter that is not in :data:`CONTACT_PARAMETERS`, or
        ``pads`` not one of ``"contact"``, ``"locked"``, ``"free"``.

    See Also
    --------
    register_contact_kind, contact_kind, contact_kinds
    """

    name: str
    summary: str
    build: Callable | None = field(compare=False)
    required: tuple[str, ...] = ()
    optional: tuple[str, ...] = ()
    purpose: str = ""
    example: str = ""
    pads: str = "contact"
    needs_friction: bool = True

    def __post_init__(self) -> None:
        unknown = [p for p in (*self.required, *self.optional) if p not in CONTACT_PARAMETERS]
        if unknown:
            raise ValueError(f"ContactKind {self.name!r}: unknown parameters {unknown}; the "
                             f"contact parameters are {list(CONTACT_PARAMETERS)}")
        if self.pads not in ("contact", "locked", "free"):
            raise ValueError(f"ContactKind {self.name!r}: pads must be 'contact', 'locked' or "
                             f"'free', got {self.pads!r}")

    @property
    def parameters(self) -> tuple[str, ...]:
        """The parameters it uses, required first."""
        return (*self.required, *self.optional)

    def missing(self, values) -> list[str]:
        """Return the required parameters absent (or 0 where 0 is not allowed).

        Parameters
        ----------
        values : mapping
            Parameter name -> value (None: not given).

        Returns
        -------
        list of str
            The names missing, in the order of :attr:`required`.
        """
        return [p for p in self.required if values.get(p) is None
                or (CONTACT_PARAMETERS[p].nonzero and not values.get(p))]


_CONTACT_KINDS: dict[str, ContactKind] = {}


def register_contact_kind(kind: ContactKind) -> ContactKind:
    """Register a contact kind (its name must be new).

    Parameters
    ----------
    kind : ContactKind
        The kind.

    Returns
    -------
    ContactKind
        ``kind``.

    Raises
    ------
    ValueError
        If a different kind of the same name is registered.
    """
    known = _CONTACT_KINDS.get(kind.name)
    if known is not None and known != kind:
        raise ValueError(f"a contact kind {kind.name!r} is already registered")
    _CONTACT_KINDS[kind.name] = kind
    return kind


def contact_kinds() -> tuple[str, ...]:
    """Return the registered contact kinds, in registration order.

    Returns
    -------
    tuple of str
        The kinds' names.
    """
    return tuple(_CONTACT_KINDS)


def contact_kind(name: str) -> ContactKind:
    """Return the registered contact kind of a name.

    Parameters
    ----------
    name : str
        The kind, e.g. ``"stiction"``.

    Returns
    -------
    ContactKind

    Raises
    ------
    ValueError
        For an unknown kind (the message lists the known ones).
    """
    try:
        return _CONTACT_KINDS[name]
    except (KeyError, TypeError):
        raise ValueError(f"contact kind must be one of {contact_kinds()}, got {name!r}") from None


for _kind in (
    ContactKind("locked", "locked pads", None, pads="locked"),
    ContactKind("stiction", "the friction law's presliding spring and damper", None),
    ContactKind("viscous", "the axis' viscous-only damping, or --c",
                None, optional=("c",)),
    ContactKind("equivalent", "the friction law's describing function at --amplitude and "
                "--frequency-hz", None, required=("amplitude", "frequency_hz"),
                purpose="the vibration amplitude [m] and frequency [Hz] of the describing "
                        "function", example="--amplitude 2e-6 --frequency-hz 50"),
    ContactKind("sliding", "the friction law linearised at --speed",
                None, required=("speed",),
                purpose="the sliding speed [m/s] of the linearisation",
                example="--speed 0.03"),
    ContactKind("free", "no friction", None, pads="free", needs_friction=False),
):
    register_contact_kind(_kind)
