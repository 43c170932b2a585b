"""The design job on FE exports of growing size: what tune and its verdict cost per DOF.

Task: the table axis of ``examples/data`` (a 650 kg table on two pads, a ball screw, a motor, a
work-piece column; :func:`generate.build_table_axis`) meshed ``refine`` times finer (146 DOFs
at 1, 242 at 2, 434 at 4), exported as MatrixMarket files with its DOF map and reduced on
loading by Craig-Bampton with **every** fixed-interface mode kept (``n_modes`` = all interior
DOFs: the reduced model as large as the export, the worst case of an export that is "fully
covered"); the axis file is ``examples/data/table_axis/axis.toml`` otherwise.

For each size: ``servotune tune <axis> --json --no-plots`` in a child process (2 workers, the
default on this machine), its wall time and the largest resident memory of any of its
processes, sampled every 0.2 s from /proc (the command and its verdict workers), and the
design's status.

``speedup``: one verdict sweep (the standing regime, 100 N peak to peak, the tuned design, the
verdict's own :func:`servotune.verdict.simulate_sweep` with its second pass) on the structure
the verdict simulates (:func:`servotune.verdict.simulated_structure`: the fixed-interface modes
far above the band dropped, their static flexibility kept; its construction and receptance
check inside the timed part) against the same sweep by the same integrator on the whole
reduced model, which is what the verdict simulated before and what a user who simulates the
reduced model as it is gets. The largest size's ratio is the top-level ``speedup``: it is the
cost of keeping every mode, not a gain over a careful reduction. For that, the same sweep on
the export reduced as ``table_axis`` ships it (every fixed-interface mode up to 600 Hz, 1.5
times the band's top) is timed too (``band_reduced``; ``speedup_vs_band_reduction``, about 1 or
below: the truncation keeps more modes than that reduction, up to the drive's sampling rate).
Peaks of all three reported. A short sweep first loads the compiled kernels.

Run: ``python benchmarks/verdict_scaling.py [--json] [--refine 1,2,4] [--no-tune]``.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import re  # noqa: E402
import shutil  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "examples" / "data" / "table_axis"
sys.path.insert(0, str(ROOT / "examples" / "data"))

import generate  # noqa: E402


def write_axis(folder: Path, refine: int) -> int:
    """The refined export with every fixed-interface mode kept; returns its DOF count."""
    mass, stiffness, dofs = generate.build_table_axis(refine)
    folder.mkdir(parents=True)
    (folder / "M.mtx").write_text(generate._matrix_market(mass))
    (folder / "K.mtx").write_text(generate._matrix_market(stiffness))
    (folder / "dofs.csv").write_text(generate._csv(
        ("index", "name"), [(i + 1, name) for i, name in enumerate(dofs)]))
    shutil.copy(TABLE / "stribeck.csv", folder / "stribeck.csv")
    text = (TABLE / "axis.toml").read_text()
    boundary = re.search(r"boundary = \[(.*?)\]", text, re.DOTALL).group(1)
    n_boundary = len(re.findall(r'"[^"]+"', boundary))
    text = re.sub(r"^f_max_hz = .*$", f"n_modes = {len(dofs) - n_boundary}", text,
                  flags=re.MULTILINE)
    text = re.sub(r'^name = "table_axis"', f'name = "table_axis_{len(dofs)}"', text,
                  flags=re.MULTILINE)
    (folder / "axis.toml").write_text(text)
    return len(dofs)


def _tree(pid):
    out = [pid]
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/children") as f:
                for child in f.read().split():
                    out += _tree(int(child))
    except OSError:
        pass
    return out


def _rss(pid) -> int:
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def run_tune(axis: Path, out: Path) -> dict:
    """``servotune tune`` in a child process: wall time, peak memory, the result."""
    cmd = [str(Path(sys.executable).parent / "servotune"), "tune", str(axis), "--json",
           "--no-plots", "--out", str(out)]
    t0 = time.perf_counter()
    with tempfile.TemporaryFile() as stdout:
        proc = subprocess.Popen(cmd, stdout=stdout, stderr=subprocess.DEVNULL)
        peak_one = peak_all = 0
        while proc.poll() is None:
            sizes = [_rss(p) for p in _tree(proc.pid)]
            peak_one, peak_all = max(peak_one, max(sizes)), max(peak_all, sum(sizes))
            time.sleep(0.2)
        wall = time.perf_counter() - t0
        stdout.seek(0)
        result = json.loads(stdout.read() or b"{}")
    verdict = result.get("verdict") or {}
    sims = [s for r in verdict.get("regimes", []) for s in r.get("simulations", [])]
    line = next((c for c in verdict.get("checked", []) if "structure simulated" in c), "")
    return {"wall_s": wall, "peak_process_bytes": peak_one, "peak_total_bytes": peak_all,
            "status": result.get("status"), "exit_status": proc.returncode,
            "optimiser_s": (result.get("solver") or {}).get("time_s"),
            "simulations": len(sims),
            "simulation_wall_s": sum(s.get("wall_time_s") or 0.0 for s in sims),
            "simulated": line.partition("structure simulated: ")[2], "design": result.get("design")}


def sweep_pair(axis_path: Path, design: dict | None, refine: int) -> dict:
    """One standing verdict sweep on the simulated, the whole and the band-reduced structure."""
    import dataclasses

    import servotune as st
    from servotune.design import tuning_problem
    from servotune.simulate import truncation
    from servotune.simulate.simulator import NonlinearAxis
    from servotune.units import HZ_PER_RAD_S
    from servotune.verdict import design_axis, simulate_sweep, simulated_structure

    axis = st.load_axis(axis_path)
    problem = tuning_problem(axis, free=("c", "kv", "kp", "ti", "notch"))
    d = problem.initial_design()
    if design:
        d = dataclasses.replace(d, **{k: v for k, v in design.items() if hasattr(d, k)})
    whole = design_axis(axis, problem, d)
    whole = NonlinearAxis(axis.structure, whole.drive, whole.pads, whole.friction)
    band_folder = axis_path.parent / f"band_{refine}"
    if not band_folder.exists():
        shutil.copytree(axis_path, band_folder)
        toml = band_folder / "axis.toml"
        toml.write_text(re.sub(r"^n_modes = .*$", "f_max_hz = 600.0", toml.read_text(),
                               flags=re.MULTILINE))
    band_structure = st.load_axis(band_folder).structure
    band = tuple(b * HZ_PER_RAD_S for b in problem.requirements.band)
    tags = {"regime": "standing", "design": "after"}
    simulate_sweep(whole, 100.0, (band[0], band[0] * 1.5), [], 0.0, None, tags, max_passes=1)

    def simulated():
        truncation._CACHE.clear()
        structure = simulated_structure(axis, problem).structure
        return NonlinearAxis(structure, whole.drive, whole.pads, whole.friction)

    cases = (("simulated", simulated),
             ("whole", lambda: whole),
             ("band_reduced", lambda: NonlinearAxis(band_structure, whole.drive, whole.pads,
                                                    whole.friction)))
    out = {}
    for name, build in cases:
        t0 = time.perf_counter()
        nl = build()
        sim = simulate_sweep(nl, 100.0, band, [], 0.0, None, tags, max_passes=2)
        out[name] = {"wall_s": time.perf_counter() - t0, "peak_m_per_n": sim.peak,
                     "resonance_hz": sim.resonance_hz, "simulated_s": sim.duration,
                     "dofs": len(nl.structure.dofs), "error": sim.error}
    out["speedup"] = out["whole"]["wall_s"] / out["simulated"]["wall_s"]
    out["speedup_vs_band_reduction"] = out["band_reduced"]["wall_s"] / out["simulated"]["wall_s"]
    out["peak_difference"] = abs(out["simulated"]["peak_m_per_n"]
                                 / out["whole"]["peak_m_per_n"] - 1.0)
    out["peak_difference_band_reduced"] = abs(out["band_reduced"]["peak_m_per_n"]
                                              / out["whole"]["peak_m_per_n"] - 1.0)
    return out


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--refine", default="1,2,4",
                        help="mesh refinements (comma-separated positive integers)")
    parser.add_argument("--no-tune", action="store_true",
                        help="only the sweep comparison (the initial design)")
    args = parser.parse_args(argv)
    try:
        refines = [int(r) for r in args.refine.split(",")]
        if any(r < 1 for r in refines):
            raise ValueError
    except ValueError:
        parser.error(f"--refine: comma-separated positive integers, got {args.refine!r}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for refine in refines:
            folder = Path(tmp) / f"axis_{refine}"
            n = write_axis(folder, refine)
            row = {"refine": refine, "dofs": n}
            if not args.no_tune:
                row["tune"] = run_tune(folder, Path(tmp) / "out")
            row["sweep"] = sweep_pair(folder, (row.get("tune") or {}).get("design"), refine)
            rows.append(row)
            if not args.json:
                t = row.get("tune") or {}
                print(f"{n} DOFs: tune {t.get('wall_s', float('nan')):.1f} s, "
                      f"peak process {t.get('peak_process_bytes', 0) / 1e9:.2f} GB, "
                      f"{t.get('status')}; sweep {row['sweep']['speedup']:.2f}x against the "
                      f"whole model, {row['sweep']['speedup_vs_band_reduction']:.2f}x against "
                      f"the band reduction (peaks {row['sweep']['peak_difference']:.1e} and "
                      f"{row['sweep']['peak_difference_band_reduced']:.1e} from the whole "
                      "model's)", flush=True)
    report = {"benchmark": "verdict_scaling", "speedup": rows[-1]["sweep"]["speedup"],
              "speedup_vs_band_reduction": rows[-1]["sweep"]["speedup_vs_band_reduction"],
              "baseline": "the same verdict sweep on the whole reduced model (every "
                          "fixed-interface mode kept, no truncation)",
              "rows": rows}
    if args.json:
        print(json.dumps(report))
    return report


if __name__ == "__main__":
    main()
