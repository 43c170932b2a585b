"""Figure captions: what a figure draws, made by the function that drew it.

A plotting function attaches its caption to the figure (:func:`set_caption`); the report shows
it under the figure and stores it in the PNG. The helpers read what was actually drawn from
the axes (:func:`drawn_labels`, :func:`style_key`), so a caption cannot promise a curve that
is absent.
"""

from __future__ import annotations

from matplotlib.figure import Figure

__all__ = ["drawn_labels", "figure_caption", "ls_name", "set_caption", "style_key"]


#: names of matplotlib's line styles, for captions
_LINE_STYLES = {"-": "solid", "solid": "solid", "--": "dashed", "dashed": "dashed",
                ":": "dotted", "dotted": "dotted", "-.": "dash-dotted", "dashdot": "dash-dotted"}


def ls_name(ls: str) -> str:
    """Return the name of a matplotlib line style.

    Parameters
    ----------
    ls : str
        The line style (``"--"``, ``"dashed"``, ...).

    Returns
    -------
    str
        Its name in a caption (``"dashed"``); an unknown style as given.
    """
    return _LINE_STYLES.get(ls, str(ls))


def set_caption(fig: Figure, text: str) -> Figure:
    """Attach a caption to a figure (read back with :func:`figure_caption`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    text : str
        What the figure draws, which regime or model, and what its line styles mean.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig``.
    """
    fig.servotune_caption = str(text)
    return fig


def figure_caption(fig: Figure) -> str:
    """Return the caption a plotting function attached to its figure ("" without one).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.

    Returns
    -------
    str
        The caption.
    """
    return getattr(fig, "servotune_caption", "")


def drawn_labels(ax) -> list[str]:
    """The legend labels of the lines drawn in an axes (with data; hidden labels left out).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.

    Returns
    -------
    list of str
        The labels, in drawing order.
    """
    return [line.get_label() for line in ax.get_lines()
            if not line.get_label().startswith("_") and len(line.get_xdata()) > 0]


def style_key(ax) -> list[str]:
    """What the line styles of an axes mean, from the curves drawn there (two points or more,
    with a legend label), each label in double quotes: ``['solid (1): "after, standing"',
    'dashed (1): "before, standing"']``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.

    Returns
    -------
    list of str
        One entry per line style drawn, naming its curves.
    """
    groups: dict[str, list[str]] = {}
    for line in ax.get_lines():
        label = line.get_label()
        if label.startswith("_") or len(line.get_xdata()) < 2 or line.get_linestyle() in (
                "None", "", " ", "none"):
            continue
        groups.setdefault(ls_name(line.get_linestyle()), []).append(label)
    return [f"{style} ({len(labels)}): " + ", ".join(f'"{x}"' for x in labels)
            for style, labels in groups.items()]
