"""How much the identified friction's spread moves the damping and the compliance of the axis.

Goal: the paper identifies its LuGre parameters in six tests and reports their spread ("var"
column, Bianchi et al. 2014, table after Fig 8): Fs +- 258 N, sigma0 +- 1.17e9 N/m,
sigma1 +- 1.3e6 N s/m (:data:`servotune.friction.BIANCHI2014_SPREAD`). This study runs every
combination of {-var, nominal, +var} of the three (27 cases; or one at a time, 7) on the
bundled paper axis and reports, per case,

* the closed-loop work-piece X compliance peak with the pads on the presliding (stiction)
  linearisation, the small-vibration limit (Table 3, stiction rows);
* the LuGre describing function (Ceq, Keq; Eq 8-10 with the full LuGre element) at a few
  vibration amplitudes at 57 Hz (the pads-locked resonance of Table 3), beside the closed-form
  Ceq of the idealised stiction cycle;
* the closed-loop compliance peak with the pads as that describing function, per amplitude.

The cases go through any :class:`concurrent.futures.Executor` (threads, processes, or a cluster
executor with the same interface): each is one call of the top-level function
:func:`evaluate_case` on plain data (a path, a dict of floats, tuples), so it pickles. Without
an executor the cases run one after the other in the calling thread.

Data source: ``models/paper_x_axis`` and the paper's identified set and spread.
"""

import itertools
import math
from pathlib import Path

import numpy as np

import servotune as st
from servotune import analysis
from servotune.friction import BIANCHI2014, BIANCHI2014_SPREAD
from servotune.friction.guideway import GuideWayFriction
from servotune.plant import Contact, friction_contact

PAPER_AXIS = Path(__file__).resolve().parents[1] / "models" / "paper_x_axis"
#: Vibration amplitudes [m] of the describing function: well inside presliding (sigma0 A << Fs),
#: around the presliding displacement Fs/sigma0 (about 1 um) and the stiction cycle's best
#: damping 2 Fs/sigma0, and in gross sliding.
AMPLITUDES = (2e-8, 5e-7, 2e-6, 1e-5, 5e-5)
FREQUENCY_HZ = 57.0
#: Frequency grid of the compliance peaks [Hz]: the requirement band of the axis, 5-300 Hz.
GRID_HZ = (5.0, 300.0, 1500)
VARIED = ("fs", "sigma0", "sigma1")


def evaluate_case(axis_path: str, params: dict, amplitudes: tuple, frequency_hz: float,
                  grid_hz: tuple = GRID_HZ) -> dict:
    """One case of the study: plain data in, plain data out (SI; frequencies in Hz).

    Parameters
    ----------
    axis_path : str
        Axis folder.
    params : dict
        The seven LuGre parameters (axis totals) of the case.
    amplitudes : tuple of float
        Vibration amplitudes [m] of the describing function.
    frequency_hz : float
        Its frequency [Hz].
    grid_hz : (low, high, count)
        Log grid of the compliance peaks [Hz].
    """
    # the paper's model: the drive in continuous time (its Table 3 calibration)
    axis = st.load_axis(axis_path).with_continuous_drive()
    friction = GuideWayFriction(axis.pads, st.LuGreParameters(**params))
    omega = 2 * math.pi * np.geomspace(*grid_hz[:2], int(grid_hz[2]))
    w = 2 * math.pi * frequency_hz
    p = friction.lugre

    stiction = analysis.compliance_curve(axis, friction_contact(friction, "stiction"), omega=omega)
    ceq, keq = st.describing_function(p, np.asarray(amplitudes, dtype=float), w)
    closed = st.equivalent_damping_stiction(p.fs, p.sigma0, np.asarray(amplitudes), w)
    peaks, where = [], []
    for a, c, k in zip(amplitudes, ceq, keq, strict=True):
        # as friction_contact(..., "equivalent"): a negative first-harmonic stiffness is
        # dropped (Contact takes passive elements only)
        curve = analysis.compliance_curve(axis, Contact.equivalent(float(c), max(float(k), 0.0),
                                                                   a), omega=omega)
        peaks.append(curve.peak_compliance)
        where.append(curve.peak_frequency / (2 * math.pi))
    return {
        "params": dict(params),
        "stiction_peak_compliance": stiction.peak_compliance,
        "stiction_peak_frequency_hz": stiction.peak_frequency / (2 * math.pi),
        "ceq_lugre": [float(c) for c in ceq],
        "keq_lugre": [float(k) for k in keq],
        "ceq_stiction_closed_form": [float(c) for c in closed],
        "equivalent_peak_compliance": peaks,
        "equivalent_peak_frequency_hz": where,
    }


def study_cases(design="factorial", nominal=BIANCHI2014, spread=BIANCHI2014_SPREAD,
                varied=VARIED) -> list[tuple[tuple[int, ...], dict]]:
    """The cases as ``(levels, parameter dict)``, levels in multiples of the spread, the
    nominal set first: every combination of -1, 0, +1 (``design="factorial"``, 27 cases) or
    one parameter at a time (``"one_at_a_time"``, 7 cases)."""
    if design == "factorial":
        combos = itertools.product((-1, 0, 1), repeat=len(varied))
    elif design == "one_at_a_time":
        combos = [tuple(level if j == i else 0 for j in range(len(varied)))
                  for i in range(len(varied)) for level in (-1, 1)] + [(0,) * len(varied)]
    else:
        raise ValueError(f"design must be 'factorial' or 'one_at_a_time', got {design!r}")
    combos = sorted(combos, key=lambda c: (any(c), c))
    cases = []
    for combo in combos:
        params = nominal.to_dict()
        for name, level in zip(varied, combo, strict=True):
            params[name] += level * spread[name]
        cases.append((combo, params))
    return cases


def main(executor=None, design="factorial", axis_path=PAPER_AXIS, amplitudes=AMPLITUDES,
         frequency_hz=FREQUENCY_HZ):
    """Run the study; ``executor`` is any ``concurrent.futures.Executor`` (None: serially in
    this thread); ``design`` as in :func:`study_cases`."""
    cases = study_cases(design)
    args = [(str(axis_path), params, tuple(amplitudes), float(frequency_hz))
            for _, params in cases]
    if executor is None:
        results = [evaluate_case(*a) for a in args]
    else:
        futures = [executor.submit(evaluate_case, *a) for a in args]
        results = [f.result() for f in futures]
    rows = [{"levels": dict(zip(VARIED, combo, strict=True)), **r}
            for (combo, _), r in zip(cases, results, strict=True)]

    def spread_of(key, index=None):
        values = np.array([r[key] if index is None else r[key][index] for r in rows])
        nominal = values[0]
        return {"nominal": float(nominal), "min": float(values.min()),
                "max": float(values.max()),
                "relative_range": float((values.max() - values.min()) / nominal)}

    summary = {"stiction_peak_compliance": spread_of("stiction_peak_compliance"),
               "by_amplitude": [{"amplitude": a,
                                 "ceq_lugre": spread_of("ceq_lugre", i),
                                 "equivalent_peak_compliance":
                                     spread_of("equivalent_peak_compliance", i)}
                                for i, a in enumerate(amplitudes)]}
    return {"design": design, "amplitudes": tuple(amplitudes), "frequency_hz": frequency_hz,
            "spread": dict(BIANCHI2014_SPREAD), "rows": rows, "summary": summary}


if __name__ == "__main__":
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(max_workers=2) as pool:
        result = main(pool)
    s = result["summary"]
    print(f"{len(result['rows'])} cases: Fs, sigma0, sigma1 at nominal +- the paper's spread "
          f"{result['spread']}")
    st_peak = s["stiction_peak_compliance"]
    print(f"closed-loop compliance peak, pads in presliding: {st_peak['nominal']:.4g} m/N "
          f"(range {st_peak['min']:.4g} .. {st_peak['max']:.4g}, "
          f"{100 * st_peak['relative_range']:.1f} % of nominal)")
    print(f"describing function at {result['frequency_hz']:g} Hz:")
    print(f"{'A [um]':>8} {'Ceq nominal':>12} {'Ceq range':>21} {'peak nominal':>13} "
          f"{'peak range':>21}")
    for b in s["by_amplitude"]:
        c, p = b["ceq_lugre"], b["equivalent_peak_compliance"]
        print(f"{1e6 * b['amplitude']:8.3g} {c['nominal']:12.4g} {c['min']:10.4g}.."
              f"{c['max']:<10.4g} {p['nominal']:13.4g} {p['min']:10.4g}..{p['max']:<10.4g}")
