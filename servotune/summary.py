"""What a tuning job says, as tables: one source for the command's text and the HTML report.

Each function returns a :class:`Table` (a title, column heads, rows of already formatted cells
and notes), so that the text output and the report cannot disagree; :func:`text` and
:func:`html_table` render it.
"""

from __future__ import annotations

import html as _html
import math
from dataclasses import dataclass, field

from .drive import kv_to_m_per_min_per_mm
from .units import HZ_PER_RAD_S

__all__ = ["Table", "inputs_table", "design_table", "regimes_table", "rounds_table", "design_line",
           "baseline_table", "loops_table", "thrust_table", "realisation_table",
           "verdict_lines", "text", "html_table", "realised_notes", "REALISED_NOTE"]



@dataclass(frozen=True)
class Table:
    """A table of the summary, printed as text (:func:`text`) or HTML (:func:`html_table`).

    Attributes
    ----------
    title : str
        The table's title.
    head : tuple of str
        Column headings (all empty: no heading row).
    rows : tuple of tuple of str
        The rows, cells already formatted.
    notes : tuple of str
        Notes printed under the table, one per line.
    """

    title: str
    head: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    notes: tuple[str, ...] = field(default=())


def _f(value, fmt="{:.4g}", none="-", inf="unstable"):
    """A value for a table: ``none`` for None, nan or -inf, ``inf`` for +inf (an unstable
    model's peak; a margin without a crossover passes its own word)."""
    if value is None:
        return none
    if isinstance(value, float) and not math.isfinite(value):
        return inf if value > 0 else none
    return fmt.format(value)


def inputs_table(job) -> Table:
    """Return the inputs and requirements the design answers to.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table
        The axis, the drive, the regimes and the requirements.
    """
    axis, problem = job.axis, job.result.problem
    req = problem.requirements
    rows = [("axis", axis.name, axis.description)]
    drive = problem.drive
    if drive is not None:
        s = drive.digital
        if s.is_continuous:
            rows.append(("drive", "continuous (no sampling, no delays: the paper's model)", ""))
        else:
            rows.append(("drive", f"sampled: current {s.current_period * 1e6:g} us, velocity "
                         f"{s.velocity_period * 1e6:g} us, position {s.position_period * 1e3:g} ms",
                         f"modelled as the sampled-data system: voltage held, outputs "
                         f"applied {s.computation_delay} period(s) after sampling, PI by "
                         f"{s.integral_rule.replace('_', ' ')}, speed from the angle difference"))
        if drive.limits is not None:
            rows.append(("thrust", f"{drive.thrust_peak / 1e3:.3g} kN peak, "
                         f"{drive.thrust_continuous / 1e3:.3g} kN continuous",
                         f"{drive.limits.torque_peak:g} / {drive.limits.torque_continuous:g} "
                         f"N m over r = {drive.ratio:.4g} m/rad"))
    op = axis.operation
    if op is not None:
        rows.append(("operation", ", ".join(f"feeding {v * 1e3:.3g} mm/s" for v in
                                            op.feed_speeds) or "no feeding regime",
                     ("standing too; " if op.standing else "")
                     + (f"rapid {op.rapid_speed:.3g} m/s at {op.acceleration:g} m/s^2"
                        if op.rapid_speed else "no rapid speed")
                     + (f"; process force {op.process_force_pp:.4g} N p-p"
                        if op.process_force_pp else "")))
    rows.append(("requirements",
                 f"Ms velocity <= {req.ms_limit('velocity'):.3f}, position <= "
                 f"{req.ms_limit('position'):.3f}",
                 f"hierarchy: velocity >= {req.bandwidth_ratio_min:g} x position bandwidth, "
                 f"current >= {req.current_bandwidth_ratio_min:g} x velocity; Ti x velocity "
                 f"bandwidth in [{req.ti_bandwidth_min:g}, {req.ti_bandwidth_max or math.inf:g}]"
                 f"; thrust reserve {req.thrust_margin:.0%}; nonlinear tolerance "
                 f"{req.nonlinear_tolerance:.0%}; band {req.band[0] * HZ_PER_RAD_S:.3g}-"
                 f"{req.band[1] * HZ_PER_RAD_S:.3g} Hz"))
    rows += setting_rows(req)
    notes = tuple(f"default taken: {d}" for d in job.notes)
    return Table("Inputs and requirements", ("", "", ""), tuple(rows), notes)


def setting_rows(requirements) -> list[tuple[str, str, str]]:
    """Return one row per requirement of another package that declares settings: its
    settings' values (the axis file's or the declared defaults) with units and ranges.

    Parameters
    ----------
    requirements : servotune.requirements.Requirements
        The requirements of the problem.

    Returns
    -------
    list of (str, str, str)
        ``(requirement, values, help)``; empty when no installed requirement declares any.
    """
    from .tuning.constraint import declared_settings

    by_owner: dict[str, list] = {}
    for key, (setting, owner) in sorted(declared_settings().items()):
        by_owner.setdefault(owner, []).append((key, setting))
    rows = []
    for owner, items in by_owner.items():
        values, helps = [], []
        for key, setting in items:
            value = requirements.value(setting)
            given = key in dict(requirements.settings)
            values.append(f"{key} = " + ("off (not given)" if value is None else
                                         f"{value:g} {setting.unit}"
                                         + ("" if given else " (default)")))
            helps.append(f"{key}: {setting.help}, in [{setting.low:g}, {setting.high:g}] "
                         f"{setting.unit}")
        rows.append((f"requirement {owner}", "; ".join(values), "; ".join(helps)))
    return rows


def design_table(job) -> Table:
    """Return the design variables and the worst claimed compliance, before and after.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table
        C, Kv, Kp, Ti and the worst claimed compliance peak, before and after.
    """
    r = job.result
    d0, d1 = r.initial, r.design
    rows = [("C guide ways [N s/m]", _f(d0.c), _f(d1.c))]
    if d0.kv is not None:
        rows += [("Kv [1/s]", _f(d0.kv), _f(d1.kv)),
                 ("Kv [(m/min)/mm]", _f(kv_to_m_per_min_per_mm(d0.kv), "{:.3g}"),
                  _f(kv_to_m_per_min_per_mm(d1.kv), "{:.3g}")),
                 ("Kp velocity [N m s/rad]", _f(d0.kp), _f(d1.kp)),
                 ("Ti velocity [s]", _f(d0.ti), _f(d1.ti))]
    if d1.notch is not None:
        n0, n1 = d0.notch, d1.notch

        def off(n, text):
            return "none" if n is None or n.depth >= 1.0 - 1e-9 else text

        rows += [("tuned notch [Hz]", off(n0, _f(n0 and n0.f_hz, "{:.1f}")),
                  off(n1, _f(n1.f_hz, "{:.1f}"))),
                 ("  width, depth [-]", off(n0, f"{n0.width:.3g}, {n0.depth:.3g}" if n0 else ""),
                  off(n1, f"{n1.width:.3g}, {n1.depth:.3g}"))]
    if d1.lowpass_frequency is not None:
        rows.append(("tuned low-pass [Hz]",
                     "none" if d0.lowpass_frequency is None else
                     _f(d0.lowpass_frequency * HZ_PER_RAD_S, "{:.4g}"),
                     _f(d1.lowpass_frequency * HZ_PER_RAD_S, "{:.4g}")))
    after = r.after
    w0 = r.before.worst_model
    w1 = None if after is None else after.worst_model
    rows += [("worst compliance peak [m/N]", _f(r.before.peak_compliance),
              _f(None if after is None else after.peak_compliance)),
             ("  in the model", "-" if w0 is None or not r.before.stable else w0.model.name,
              "-" if w1 is None else w1.model.name),
             ("  at [Hz]", _f(r.before.peak_frequency * HZ_PER_RAD_S, "{:.1f}")
              if r.before.stable else "-",
              "-" if after is None else _f(after.peak_frequency * HZ_PER_RAD_S, "{:.1f}"))]
    if r.before.b_crit is not None or (after is not None and after.b_crit is not None):
        rows.append(("b_crit [mm] (worst model)",
                     _f(None if r.before.b_crit is None else r.before.b_crit * 1e3, "{:.3g}"),
                     _f(None if after is None or after.b_crit is None else after.b_crit * 1e3,
                        "{:.3g}")))
    notes = []
    if not r.before.stable:
        bad = [m.model.name for m in r.before.models if not m.stable]
        notes.append("the initial design is unstable in: " + ", ".join(bad)
                     + (" (as the sampled-data system the digital drive is)"
                        if r.problem.drive is not None
                        and not r.problem.drive.digital.is_continuous else ""))
        if job.kp_limit is not None:
            k = job.kp_limit
            notes.append(f"the sampled-data velocity loop of {k['model']} is stable only up to "
                         f"Kp = {k['kp_max']:.4g} N m s/rad at Ti = {k['ti'] * 1e3:.4g} ms "
                         f"(position loop open); the initial Kp is {k['kp_initial']:.4g}")
        if r.start is not None and r.start != r.initial:
            notes.append(f"the tuning started from a softer velocity loop: Kp = "
                         f"{r.start.kp:.4g} N m s/rad")
    elif r.start is not None and r.start != r.initial:
        notes.append(f"the tuning started from C = {r.start.c:.4g} N s/m, Kv = "
                     f"{r.start.kv:.4g} 1/s, Kp = {r.start.kp:.4g} N m s/rad, Ti = "
                     f"{r.start.ti * 1e3:.4g} ms")
    given = getattr(job, "as_given", None)
    if given is not None:
        g, ci = given["design"], given["current_loop"]
        state = ("unstable in " + ", ".join(given["unstable_in"]) if given["unstable_in"]
                 else "stable in every nominal model")
        notes.append(f"the axis as given (C {g['c']:.4g} N s/m, Kv {g['kv']:.4g} 1/s, Kp "
                     f"{g['kp']:.4g} N m s/rad, Ti {g['ti'] * 1e3:.4g} ms, current loop "
                     f"{ci['kp']:.4g} V/A, {ci['ti'] * 1e3:.4g} ms) is {state}")
        k = given.get("kp_limit")
        if k is not None:
            notes.append(f"as given, the sampled-data velocity loop of {k['model']} is "
                         f"stable only up to Kp = {k['kp_max']:.4g} N m s/rad at Ti = "
                         f"{k['ti'] * 1e3:.4g} ms (position loop open); the axis gives "
                         f"{k['kp_initial']:.4g}")
    if r.active:
        notes.append("active at the optimum: " + "; ".join(r.active))
    for model, why in r.excluded:
        notes.append(f"left out of the tuning: {model.name}: {why}")
    return Table("Design", ("", "before", "after"), tuple(rows), tuple(notes))


def regimes_table(job) -> Table:
    """Return, regime by regime, the claim, the nonlinear axis before and after, the improvement.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table
        One row per regime.
    """
    rows = []
    verdict = job.verdict
    if verdict is not None and verdict.regimes:
        for v in verdict.regimes:
            imp = v.realised_improvement
            rows.append((v.name, _f(v.claimed_peak_before, "{:.3g}"), _f(v.claimed_peak, "{:.3g}"),
                         _f(v.nonlinear_peak_before, "{:.3g}",
                            none="unstable" if not job.result.before.stable else "-"),
                         _f(v.nonlinear_peak_after, "{:.3g}"),
                         "-" if imp is None else f"{imp:.2f}x",
                         "yes" if v.holds else "NO"))
        notes = tuple(f"{v.name}: {v.reason}" for v in verdict.regimes if not v.holds)
        notes += tuple(f"{v.name}: {v.explanation}" for v in verdict.regimes if v.explanation)
        notes += realised_notes(verdict.regimes, verdict.tolerance)
    else:
        for entry in _linear_claims(job):
            rows.append((entry[0], _f(entry[1], "{:.3g}"), _f(entry[2], "{:.3g}"), "-", "-",
                         "-", "linear" if verdict is not None else "not simulated"))
        notes = (("the nonlinear verification was skipped",) if verdict is None else
                 tuple(verdict.checked))
    return Table("Regimes: worst compliance peak [m/N], linear claim and nonlinear axis",
                 ("regime", "claim before", "claim after", "nonlinear before",
                  "nonlinear after", "realised", "holds"), tuple(rows), notes)


#: what the "realised" column of :func:`regimes_table` is
REALISED_NOTE = ("realised: the nonlinear axis' worst peak before over after tuning, at the "
                 "nominal friction (1.10x: 10% lower after); it measures the improvement "
                 "the nonlinear axis shows, not the claim: 'holds' compares the peak after "
                 "(over the friction spread too) with the claim")


def realised_notes(regimes, tolerance: float) -> tuple[str, ...]:
    """Return the notes that explain the "realised" column, regime by regime where it could
    be misread (an improvement beside a claim that does not hold).

    Parameters
    ----------
    regimes : sequence of servotune.verdict.RegimeVerdict
        The regimes of the verdict.
    tolerance : float
        The verdict's tolerance on the claim.

    Returns
    -------
    tuple of str
        :data:`REALISED_NOTE` (when a regime has a realised improvement) and, for each regime
        that does not hold, what its realised value means there.
    """
    regimes = list(regimes)
    if not any(v.realised_improvement is not None for v in regimes):
        return ()
    notes = [REALISED_NOTE]
    for v in regimes:
        imp = v.realised_improvement
        if v.holds or imp is None:
            continue
        change = ("unchanged" if abs(imp - 1) < 0.005 else
                  f"{1 - 1 / imp:.0%} lower" if imp > 1 else f"{1 / imp - 1:.0%} higher")
        after = (v.nonlinear_peak_after_nominal if v.nonlinear_peak_after_nominal is not None
                 else v.nonlinear_peak_after)
        notes.append(f"{v.name}: realised {imp:.2f}x: the nominal friction's nonlinear peak is "
                     f"{change} after tuning ({_f(v.nonlinear_peak_before, '{:.3g}')} -> "
                     f"{_f(after, '{:.3g}')} m/N), yet the claim "
                     f"{_f(v.claimed_peak, '{:.3g}')} m/N does not hold within "
                     f"{tolerance:.0%} (see the reason above)")
    return tuple(notes)


def baseline_table(job) -> Table | None:
    """Return the tuned design against the baselines, regime by regime, linear and nonlinear.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table or None
        One row per regime: the claim (linear) and the nonlinear peak of the commissioning
        engineer's design, the textbook's and the tuned one, and the tuned against the
        commissioning (None without baselines).
    """
    base = getattr(job, "baseline", None)
    if not base:
        return None
    # like with like: the nominal friction (the baselines are judged there)
    tuned = {}
    for mp in job.result.after.models if job.result.after is not None else ():
        m = mp.model
        if not m.cutting or m.sample != "nominal":
            continue
        peak = mp.peak_compliance if mp.stable else math.inf
        tuned[m.regime] = (max(tuned.get(m.regime, (0.0,))[0], peak or 0.0), None)
    if job.verdict is not None:
        for v in job.verdict.regimes:
            if v.name in tuned:
                nominal = getattr(v, "nonlinear_peak_after_nominal", None)
                tuned[v.name] = (tuned[v.name][0],
                                 nominal if nominal is not None else v.nonlinear_peak_after)
    com = {r["name"]: r for r in base["commissioning"]["regimes"]}
    txt = {r["name"]: r for r in base["textbook"]["regimes"]}
    rows = []
    for name, (claim, nonlinear) in tuned.items():
        c, t = com.get(name, {}), txt.get(name, {})

        def change(a, b):
            if a is None or b is None or not (math.isfinite(a) and math.isfinite(b)):
                return "-"
            return f"{100 * (a / b - 1):+.0f} %"

        rows.append((name, _f(c.get("claimed_peak_m_per_n"), "{:.3g}"),
                     _f(c.get("nonlinear_peak_m_per_n"), "{:.3g}"),
                     _f(t.get("claimed_peak_m_per_n"), "{:.3g}"),
                     _f(t.get("nonlinear_peak_m_per_n"), "{:.3g}"),
                     _f(claim, "{:.3g}"), _f(nonlinear, "{:.3g}"),
                     change(claim, c.get("claimed_peak_m_per_n")),
                     change(nonlinear, c.get("nonlinear_peak_m_per_n"))))
    d = base["commissioning"]["design"] or {}
    notes = [f"commissioning ({d.get('rule', 'servotune.baseline')}): current PI "
             f"{d['current_kp']:.4g} V/A, {d['current_ti'] * 1e3:.4g} ms; velocity PI "
             f"{d['velocity_kp']:.4g} N m s/rad, {d['velocity_ti'] * 1e3:.4g} ms; Kv "
             f"{d['kv']:.4g} 1/s; C {d['c']:.4g} N s/m"
             + "".join(f"; notch {n['f_hz']:.4g} Hz" for n in d.get("notches") or ())
             + (f"; low-pass {d['lowpass']['f_hz']:.4g} Hz" if d.get("lowpass") else "")
             if all(k in d for k in ("current_kp", "velocity_kp", "kv", "c")) else
             "commissioning: servotune.baseline (technical and symmetric optimum, a notch, "
             "Kv from the hierarchy)",
             "textbook: Kp = J 2 pi 25 Hz, Ti = 25 ms, Kv = 25 1/s",
             "all at the nominal friction; the baselines' nonlinear peaks by harmonic balance "
             "at 1 and 3 x the process force, the tuned design's by the verdict"]
    for key in ("commissioning", "textbook"):
        if base[key].get("note"):
            notes.append(base[key]["note"])
        spread = base[key].get("spread_unstable")
        if spread:
            notes.append(f"{key}: unstable at {len(spread)} corner model(s) of the friction "
                         f"spread ({spread[0]}{' ...' if len(spread) > 1 else ''})")
        elif spread is not None:
            notes.append(f"{key}: stable at every corner of the friction spread")
    notes = tuple(notes)
    return Table("Against the baselines: worst compliance peak [m/N] per regime, linear claim "
                 "and nonlinear",
                 ("regime", "commissioning", "nonlinear", "textbook", "nonlinear", "tuned",
                  "nonlinear", "tuned vs comm.", "nonlinear"), tuple(rows), notes)


def design_line(d, kv_machine: bool = True) -> str:
    """Return a design in one line: C, Kv, Kp, Ti and its tuned filters (SI units).

    Parameters
    ----------
    d : servotune.tuning.Design
        The design.
    kv_machine : bool
        Also give Kv in the machine-tool unit (m/min)/mm.

    Returns
    -------
    str
        E.g. ``"C 5578 N s/m, Kv 52.95 1/s, Kp 5.198 N m s/rad, Ti 9.573 ms, notch 654.2 Hz
        (width 1, depth 0.01)"``; a tuned notch of depth 1 (none) is left out.
    """
    if d.kv is None:
        return f"C {d.c:.4g} N s/m"
    kv = f"Kv {d.kv:.4g} 1/s" + (f" ({kv_to_m_per_min_per_mm(d.kv):.3g} (m/min)/mm)"
                                 if kv_machine else "")
    text = f"C {d.c:.4g} N s/m, {kv}, Kp {d.kp:.4g} N m s/rad, Ti {d.ti * 1e3:.4g} ms"
    n = d.notch
    if n is not None and n.depth < 1.0 - 1e-9:
        text += f", notch {n.f_hz:.1f} Hz (width {n.width:.2g}, depth {n.depth:.2g})"
    if d.lowpass_frequency is not None:
        text += f", low-pass {d.lowpass_frequency * HZ_PER_RAD_S:.4g} Hz"
    return text


def rounds_table(job) -> Table | None:
    """Return the rounds of tuning and verification (None when there was one plain round).

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table or None
        One row per round: its design, what its check said and the models added for the next.
    """
    rounds = getattr(job, "rounds", ())
    if not rounds or (len(rounds) == 1 and not rounds[0].added):
        return None
    rows = []
    for r in rounds:
        d = r.design
        design = "-" if d is None else design_line(d, kv_machine=False)
        label = "screen" if r.number == 0 else str(r.number)
        rows.append((label, design, r.verdict if len(r.verdict) < 160 else
                     r.verdict[:157] + "...", ", ".join(r.added) or "-"))
    return Table("Rounds: a refuted operating point becomes a model of the next round",
                 ("round", "design", "check", "added to the tuning"), tuple(rows))


def _linear_claims(job):
    """(regime, claim before, claim after) from the dense check of each cutting model."""
    r = job.result
    out = {}
    for mp0, mp1 in zip(r.before.models, (r.after or r.before).models, strict=True):
        if not mp1.model.cutting:
            continue
        b = mp0.peak_compliance if mp0.stable else math.inf
        a = mp1.peak_compliance if mp1.stable else math.inf
        old = out.get(mp1.model.regime, (0.0, 0.0))
        out[mp1.model.regime] = (max(old[0], b), max(old[1], a))
    return [(name, b, a) for name, (b, a) in out.items()]


def loops_table(job) -> Table | None:
    """Return both loops of the reference model (where the axis moves), before and after.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table or None
        Margins, Ms and bandwidths of the velocity and position loops; None without a drive.
    """
    r = job.result
    if r.problem.drive is None:
        return None
    rows = []
    after = r.after
    ref = None if after is None else after.models[after.reference].model.name
    for loop in ("velocity", "position"):
        a0 = getattr(r.before, loop) if r.before.stable else None
        a1 = None if after is None else getattr(after, loop)
        if a0 is None and a1 is None:
            continue
        rows += [(f"{loop} loop Ms", _f(a0 and a0.ms, "{:.3f}"), _f(a1 and a1.ms, "{:.3f}")),
                 ("  phase margin [deg]",
                  _f(a0 and a0.phase_margin_deg, "{:.1f}", inf="no crossover"),
                  _f(a1 and a1.phase_margin_deg, "{:.1f}", inf="no crossover")),
                 ("  gain margin [dB]", _f(a0 and a0.gain_margin_db, "{:.1f}", inf="inf"),
                  _f(a1 and a1.gain_margin_db, "{:.1f}", inf="inf"))]
        if (a0 and a0.gain_margin_lower > 0) or (a1 and a1.gain_margin_lower > 0):
            rows += [("  lower gain margin [dB]", _f(a0 and a0.gain_margin_lower_db, "{:.1f}"),
                      _f(a1 and a1.gain_margin_lower_db, "{:.1f}"))]
        rows += [("  bandwidth [Hz]", _f(a0 and a0.bandwidth_hz, "{:.3g}"),
                  _f(a1 and a1.bandwidth_hz, "{:.3g}"))]
    lower = [loop for loop in ("velocity", "position") if after is not None
             and getattr(after, loop).gain_margin_lower > 0]
    if lower:
        notes = [f"the {' and '.join(lower)} loop is conditionally stable: the lower gain "
                 "margin is how far the gain may fall (an integrator or a friction that falls "
                 "with speed makes the open loop need a minimum gain)"]
    else:
        notes = []
    # every requirement judged on the reference model that the rows above do not show (the
    # loop hierarchy, Ti, the current loop, and any requirement added as a module)
    notes += [c.text for c in r.checks if c.model == ref and c.requirement not in (
        "stability", "Ms velocity loop", "Ms position loop")]
    if r.stats.current_loop_bandwidth_hz:
        notes.append(f"current loop bandwidth {r.stats.current_loop_bandwidth_hz:.4g} Hz "
                     "(rotor held)")
    sampled = r.problem.drive is not None and not r.problem.drive.digital.is_continuous
    how = ("margins of the sampled-data loops, each at its controller's rate" if sampled
           else "continuous loops")
    return Table(f"Loops ({ref or 'reference model'}; {how})",
                 ("", "before", "after"), tuple(rows), tuple(notes))


def thrust_table(job) -> Table | None:
    """Return the thrust needed against the thrust available, term by term, for the tuned design.

    One row per case of the duty (:meth:`servotune.thrust.ThrustBudget.cases`: accelerating to
    rapid speed, traversing at it, feeding, standing), each with the usable thrust at its own
    speed and the largest C it allows; the note gives the least of those, the budget's bound.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table or None
        One row per load case [kN]; None without a thrust budget.
    """
    t = job.thrust_after
    if t is None:
        return None
    limits = t.get("c_max_by_case", {})
    rows = []
    for case in t["cases"]:
        terms = ", ".join(f"{k} {v / 1e3:.3g}" for k, v in case["terms_n"].items() if v)
        rows.append((f"{case['name']} ({case['thrust']})", f"{case['usable_n'] / 1e3:.3g}",
                     f"{case['needed_n'] / 1e3:.3g}", f"{case['utilisation']:.0%}",
                     "yes" if case["fits"] else "NO", _f(limits.get(case["name"])), terms))
    binding = t.get("c_max_case")
    notes = (f"usable = {1 - t['margin']:.0%} of the motor's thrust at the case's speed "
             f"({t['margin']:.0%} kept in reserve); moving mass {t['moving_mass_kg']:.4g} kg at "
             f"the slide; the budget allows a total viscous C of up to {t['c_max']:.4g} N s/m"
             + (f", the least over the cases (set by {binding})" if binding else ""),)
    return Table("Thrust [kN]: usable, needed (at the tuned C)",
                 ("case", "usable", "needed", "of available", "fits", "C up to [N s/m]",
                  "terms [kN]"), tuple(rows), notes)


def realisation_table(job) -> Table | None:
    """Return what could build the tuned C, its cost, and whether the budget holds.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    Table or None
        One row per option; None when the job has none.
    """
    if not job.c_realisation:
        return None
    rows = []
    for x in job.c_realisation:
        rows.append((x.option, _f(x.added_damping), _f(x.force_feed, "{:.3g}"),
                     _f(x.power_feed, "{:.3g}"), _f(x.force_rapid, "{:.3g}"),
                     _f(x.power_rapid, "{:.3g}"), "yes" if x.fits else "no"))
    notes = tuple(f"{x.option}: {x.note}" for x in job.c_realisation)
    return Table("Realising C: added damping dC [N s/m], extra force [N] and power [W] at the "
                 "highest feed and at rapid traverse",
                 ("option", "dC", "force feed", "power feed", "force rapid", "power rapid",
                  "fits"), tuple(rows), notes)


def verdict_lines(job) -> tuple[str, tuple[str, ...]]:
    """Return the verdict line (label and what it means) and what was checked or not.

    Parameters
    ----------
    job : servotune.design.AxisTuning
        The tuning job (:func:`servotune.design.tune_axis`).

    Returns
    -------
    head : str
        The verdict line: VERIFIED, NOT VERIFIED (linear check only) or NOT VERIFIED with the
        reasons.
    lines : tuple of str
        What the nonlinear verification checked and did not check (empty without it).
    """
    status = job.status
    r = job.result
    if job.verdict is not None:
        head = job.verdict.headline
    elif status == "linear only":
        head = ("NOT VERIFIED (linear check only): the linear checks hold in every regime "
                "model; the nonlinear verification was skipped")
    else:
        head = "NOT VERIFIED: " + ("; ".join(r.reasons) if r.reasons else "see the checks")
    lines = []
    if job.verdict is not None and job.verdict.nonlinear_holds is not None:
        lines += [f"checked: {c}" for c in job.verdict.checked]
        lines += [f"not checked: {c}" for c in job.verdict.not_checked]
    return head, tuple(lines)


def text(table: Table | None, widths=None) -> str:
    """Return a table as aligned text lines.

    The first column is left-aligned, the others right-aligned; a table whose three headings
    are empty is a listing, whose second and third columns are not aligned.

    Parameters
    ----------
    table : Table or None
        The table.
    widths : sequence of int, optional
        Column widths [characters]; default the widest cell of each column.

    Returns
    -------
    str
        The title, the rows and the notes in parentheses, indented; "" for None.
    """
    if table is None:
        return ""
    cols = len(table.head)
    rows = [table.head, *table.rows]
    widths = widths or [max(len(str(r[i])) for r in rows) for i in range(cols)]
    out = [f"  {table.title}"]
    for k, row in enumerate(rows):
        if k == 0 and not any(table.head):
            continue
        cells = [str(c).ljust(widths[i]) if i == 0 else str(c).rjust(widths[i])
                 for i, c in enumerate(row)]
        if cols == 3 and table.head == ("", "", ""):  # a two-column listing
            cells = [str(row[0]).ljust(widths[0]), str(row[1]), str(row[2])]
        out.append("    " + "  ".join(cells).rstrip())
    out += [f"    ({n})" for n in table.notes]
    return "\n".join(out)


def html_table(table: Table | None) -> str:
    """Return a table as HTML (cells escaped).

    Parameters
    ----------
    table : Table or None
        The table.

    Returns
    -------
    str
        An HTML table with its title and notes; "" for None.
    """
    if table is None:
        return ""
    esc = _html.escape
    head = ("" if not any(table.head) else
            "<tr>" + "".join(f"<th>{esc(h)}</th>" for h in table.head) + "</tr>")
    body = "".join("<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in row) + "</tr>"
                   for row in table.rows)
    notes = "".join(f"<li>{esc(n)}</li>" for n in table.notes)
    return (f"<h2>{esc(table.title)}</h2><table>{head}{body}</table>"
            + (f"<ul class='notes'>{notes}</ul>" if notes else ""))
