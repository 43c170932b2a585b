"""servotune: design of machine-tool feed axes where servo drive, guide-way friction and
structure interact, after Bianchi et al., "Analysis of vibration damping in machine tools",
Procedia CIRP 21 (2014) 367-372.

Use as ``import servotune as st``. SI units throughout (m, N, s, kg, rad).

The names below are imported on first use (PEP 562 module ``__getattr__``), so that
``import servotune`` and the ``servotune`` command start at once; ``st.load_axis``,
``st.analysis`` and every other public name work as if imported eagerly.
"""

import importlib

# public name -> the module that defines it (imported when the name is first used)
_LAZY = {
    "Axis": ".axis",
    "AxisFormatError": ".axis",
    "Cutting": ".axis",
    "load_axis": ".axis",
    "MillingSetup": ".chatter",
    "Mode": ".chatter",
    "StabilityLobes": ".chatter",
    "StabilityMap": ".chatter",
    "absolute_stability_limit": ".chatter",
    "chatter_margin": ".chatter",
    "critical_depth": ".chatter",
    "modal_compliance": ".chatter",
    "read_frf_csv": ".chatter",
    "sdm_lobes": ".chatter",
    "stability_lobes": ".chatter",
    "stability_map": ".chatter",
    "Drive": ".drive",
    "LowPassFilter": ".drive",
    "Motor": ".drive",
    "NotchFilter": ".drive",
    "PIController": ".drive",
    "kv_from_m_per_min_per_mm": ".drive",
    "kv_to_m_per_min_per_mm": ".drive",
    "ClosedLoopPoles": ".frequency",
    "LoopAnalysis": ".frequency",
    "analyse_loop": ".frequency",
    "closed_loop_poles": ".frequency",
    "compliance": ".frequency",
    "fast_frequency_response": ".frequency",
    "following_error": ".frequency",
    "modal_receptance": ".frequency",
    "port_compliance": ".frequency",
    "BIANCHI2014": ".friction",
    "CANUDAS1995": ".friction",
    "HysteresisCycle": ".friction",
    "LuGreParameters": ".friction",
    "LuGreResponse": ".friction",
    "lugre_cycle": ".friction",
    "lugre_derivative": ".friction",
    "lugre_force": ".friction",
    "lugre_jacobian": ".friction",
    "presliding_linearisation": ".friction",
    "simulate_lugre": ".friction",
    "sliding_linearisation": ".friction",
    "steady_state_friction": ".friction",
    "stribeck_curve": ".friction",
    "micro_damping": ".friction",
    "describing_function": ".friction.equivalent",
    "equivalent_damping_stiction": ".friction.equivalent",
    "stiction_describing_function": ".friction.equivalent",
    "lugre_periodic_force": ".friction.periodic",
    "FrictionFit": ".friction.identify",
    "fit_presliding": ".friction.identify",
    "fit_steady_state": ".friction.identify",
    "Contact": ".plant",
    "GuideWayFriction": ".friction.guideway",
    "friction_contact": ".plant",
    "UnstableLoopError": ".plant",
    "build_plant": ".plant",
    "loop_transfer": ".plant",
    "NonlinearCompliance": ".harmonic",
    "nonlinear_compliance": ".harmonic",
    "Requirements": ".requirements",
    "LuGreFriction": ".simulate",
    "NonlinearAxis": ".simulate",
    "PadFriction": ".simulate",
    "Scenario": ".simulate",
    "SimulationError": ".simulate",
    "SimulationResult": ".simulate",
    "SweepEnvelope": ".simulate",
    "ViscousFriction": ".simulate",
    "WindowEnergies": ".simulate",
    "circle": ".simulate",
    "constant_speed": ".simulate",
    "point_to_point": ".simulate",
    "sine_sweep": ".simulate",
    "sinusoid": ".simulate",
    "CraigBamptonCheck": ".structure",
    "MatrixFileError": ".structure",
    "ModalModel": ".structure",
    "StructureBuilder": ".structure",
    "UnknownDofError": ".structure",
    "cb_check": ".structure",
    "craig_bampton": ".structure",
    "read_structure": ".structure",
    "write_npz": ".structure",
    "TwoMassAnalysis": ".twomass",
    "TwoMassSystem": ".twomass",
    "analyse_two_mass": ".twomass",
    "fixed_points": ".twomass",
    "g_alpha": ".twomass",
    "limit_resonances": ".twomass",
    "minimax_damping": ".twomass",
    "optimal_damping": ".twomass",
    "optimal_peak": ".twomass",
    "peak_compliance": ".twomass",
    "two_mass_compliance": ".twomass",
}

# (the function is servotune.simulate.simulate: the name servotune.simulate stays the package)

__version__ = "0.1.0"

__all__ = [
    "__version__",
    "analysis",
    "design",
    # drive
    "Drive",
    "LowPassFilter",
    "Motor",
    "NotchFilter",
    "PIController",
    "kv_from_m_per_min_per_mm",
    "kv_to_m_per_min_per_mm",
    # plant
    "Contact",
    "GuideWayFriction",
    "Requirements",
    "UnstableLoopError",
    "build_plant",
    "friction_contact",
    "loop_transfer",
    # frequency
    "ClosedLoopPoles",
    "LoopAnalysis",
    "analyse_loop",
    "closed_loop_poles",
    "compliance",
    "fast_frequency_response",
    "following_error",
    "modal_receptance",
    "port_compliance",
    # structure
    "ModalModel",
    "UnknownDofError",
    # structure: Craig-Bampton reduction, matrix files, builder; axis descriptions
    "craig_bampton",
    "cb_check",
    "CraigBamptonCheck",
    "read_structure",
    "write_npz",
    "MatrixFileError",
    "StructureBuilder",
    "Axis",
    "AxisFormatError",
    "Cutting",
    "load_axis",
    # twomass
    "TwoMassSystem",
    "TwoMassAnalysis",
    "analyse_two_mass",
    "fixed_points",
    "g_alpha",
    "limit_resonances",
    "minimax_damping",
    "optimal_damping",
    "optimal_peak",
    "peak_compliance",
    "two_mass_compliance",
    # friction
    "BIANCHI2014",
    "CANUDAS1995",
    "HysteresisCycle",
    "LuGreParameters",
    "LuGreResponse",
    "lugre_cycle",
    "lugre_derivative",
    "lugre_force",
    "lugre_jacobian",
    "presliding_linearisation",
    "simulate_lugre",
    "sliding_linearisation",
    "steady_state_friction",
    "stribeck_curve",
    "describing_function",
    "equivalent_damping_stiction",
    "stiction_describing_function",
    "FrictionFit",
    "fit_presliding",
    "fit_steady_state",
    # chatter
    "MillingSetup",
    "Mode",
    "StabilityLobes",
    "StabilityMap",
    "absolute_stability_limit",
    "chatter_margin",
    "critical_depth",
    "modal_compliance",
    "read_frf_csv",
    "sdm_lobes",
    "stability_lobes",
    "stability_map",
    # simulate
    "LuGreFriction",
    "NonlinearAxis",
    "PadFriction",
    "Scenario",
    "SimulationError",
    "SimulationResult",
    "SweepEnvelope",
    "ViscousFriction",
    "WindowEnergies",
    "circle",
    "constant_speed",
    "point_to_point",
    "sine_sweep",
    "sinusoid",
    # friction: velocity-dependent micro-damping
    "micro_damping",
    # harmonic balance: amplitude-dependent compliance
    "NonlinearCompliance",
    "lugre_periodic_force",
    "nonlinear_compliance",
]


def __getattr__(name: str):
    """Import a public name, or a subpackage such as ``servotune.analysis``, on first use."""
    module = _LAZY.get(name)
    if module is not None:
        value = getattr(importlib.import_module(module, __name__), name)
    elif not name.startswith("_"):
        try:
            value = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
