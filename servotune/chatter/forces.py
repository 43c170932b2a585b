"""The cutting force of a milling set-up: what the axis feels while it cuts.

With the chip thickness ``h_j = f_z sin(phi_j)`` of a straight-flute cutter fed by ``f_z`` per
tooth, the force on the work piece over one tooth period is the static part of the
regenerative model of :mod:`servotune.chatter.setup`::

    F(t) = -b f_z H(t) [1, 0]^T          (x = feed direction, y across it)

with the axial depth b [m] and the periodic directional matrix H(t) [N/m^2]. Its mean is what
the feed drive must push against while cutting; its oscillation about the mean (tooth-passing
frequency and harmonics) is the excitation of the structure at the work piece.

References
----------
Y. Altintas, Manufacturing Automation, 2nd ed., Cambridge University Press (2012), sec 2.4
(mechanics of milling: average and instantaneous forces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..validation import positive
from .setup import DIRECTIONS, MillingSetup, periodic_directional_matrix

__all__ = ["CuttingForce", "cutting_force"]


@dataclass(frozen=True)
class CuttingForce:
    """The cutting force in one direction over a tooth period (SI).

    Attributes
    ----------
    direction : str
    depth : float
        Axial depth of cut b [m].
    feed_per_tooth : float
        f_z [m].
    mean : float
        Mean force [N] (on the work piece, sign as the axis).
    peak_to_peak : float
        Largest minus smallest force over the tooth period [N].
    first_harmonic : float
        Amplitude of the tooth-passing harmonic [N].
    time : numpy.ndarray
        Times over one tooth period, as fractions of it [-].
    force : numpy.ndarray
        The force at those times [N].
    """

    direction: str
    depth: float
    feed_per_tooth: float
    mean: float
    peak_to_peak: float
    first_harmonic: float
    time: np.ndarray
    force: np.ndarray

    def to_dict(self) -> dict:
        """Return the scalar results as a JSON-ready dictionary (SI; forces in N).

        Returns
        -------
        dict
            JSON-ready values (str, numbers, lists, None).
        """
        return {"direction": self.direction, "depth": self.depth,
                "feed_per_tooth": self.feed_per_tooth, "mean_n": self.mean,
                "peak_to_peak_n": self.peak_to_peak, "first_harmonic_n": self.first_harmonic}


def cutting_force(setup: MillingSetup, depth: float, feed_per_tooth: float,
                  direction: str = "x", samples: int = 720) -> CuttingForce:
    """The cutting force on the work piece in ``direction`` over one tooth period.

    Parameters
    ----------
    setup : MillingSetup
        The milling set-up (teeth, cutting coefficients, immersion).
    depth : float
        Axial depth of cut b [m].
    feed_per_tooth : float
        Feed per tooth f_z [m], in the x (feed) direction.
    direction : {"x", "y"}
        Direction of the force component: "x" the feed direction, "y" normal to it.
    samples : int
        Intervals of the tooth period (the force is averaged over each, exactly).

    Returns
    -------
    CuttingForce
        The force over the period [N] and its mean, peak-to-peak and first harmonic.

    Raises
    ------
    ValueError
        When ``direction`` is not "x" or "y", or ``depth`` or ``feed_per_tooth`` is not a
        positive finite number [m].

    Examples
    --------
    In a full slot with two teeth one tooth is always cutting; the mean feed force is then
    ``-b f_z N K_n / 4`` (the tangential part averages out over the half turn):

    >>> s = MillingSetup(teeth=2, kt=6e8, kn=2e8, radial_immersion=1.0)
    >>> f = cutting_force(s, depth=2e-3, feed_per_tooth=1e-4)
    >>> round(f.mean, 6), round(-2e-3 * 1e-4 * 2 * 2e8 / 4, 6)
    (-20.0, -20.0)
    """
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    depth = positive("cutting_force:", "depth", depth, "m")
    feed_per_tooth = positive("cutting_force:", "feed_per_tooth", feed_per_tooth, "m")
    h = periodic_directional_matrix(setup, int(samples))
    row = DIRECTIONS.index(direction)
    force = -float(depth) * float(feed_per_tooth) * h[:, row, 0]
    spectrum = np.fft.rfft(force) / force.size
    return CuttingForce(direction, float(depth), float(feed_per_tooth), float(force.mean()),
                        float(force.max() - force.min()), float(2.0 * abs(spectrum[1])),
                        (np.arange(force.size) + 0.5) / force.size, force)
