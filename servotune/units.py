"""Unit conversions at the edges of servotune (everything inside is SI).

Values converted for people (Hz in plots and tables, Kv in (m/min)/mm, spindle speeds in rpm,
feed speeds in mm/s) carry the unit in their name; the factors live here and nowhere else.

Examples
--------
>>> round(100.0 * HZ_PER_RAD_S, 4)          # 100 rad/s in Hz
15.9155
>>> round(kv_from_m_per_min_per_mm(1.0), 4) # 1 (m/min)/mm in 1/s
16.6667
"""

from __future__ import annotations

import math

__all__ = ["HZ_PER_RAD_S", "RAD_S_PER_HZ", "KV_PER_M_PER_MIN_PER_MM", "RAD_S_PER_RPM",
           "kv_from_m_per_min_per_mm", "kv_to_m_per_min_per_mm"]

#: Hz per rad/s: ``f_hz = omega * HZ_PER_RAD_S``.
HZ_PER_RAD_S = 1.0 / (2.0 * math.pi)
#: rad/s per Hz: ``omega = f_hz * RAD_S_PER_HZ``.
RAD_S_PER_HZ = 2.0 * math.pi
#: Kv [1/s] per (m/min)/mm: 1 (m/min)/mm = (1/60 m/s) / (1e-3 m) = 16.67 1/s.
KV_PER_M_PER_MIN_PER_MM = 1000.0 / 60.0
#: rad/s per rpm.
RAD_S_PER_RPM = 2.0 * math.pi / 60.0


def kv_from_m_per_min_per_mm(kv_m_per_min_per_mm: float) -> float:
    """Position-loop gain Kv [1/s] from the machine-tool unit (m/min)/mm.

    Parameters
    ----------
    kv_m_per_min_per_mm : float
        Kv in (m/min)/mm (feed speed per following error).

    Returns
    -------
    float
        Kv in 1/s.

    See Also
    --------
    kv_to_m_per_min_per_mm : the inverse.
    """
    return float(kv_m_per_min_per_mm) * KV_PER_M_PER_MIN_PER_MM


def kv_to_m_per_min_per_mm(kv: float) -> float:
    """Position-loop gain in (m/min)/mm from Kv [1/s].

    Parameters
    ----------
    kv : float
        Kv in 1/s.

    Returns
    -------
    float
        Kv in (m/min)/mm.

    See Also
    --------
    kv_from_m_per_min_per_mm : the inverse.
    """
    return float(kv) / KV_PER_M_PER_MIN_PER_MM
