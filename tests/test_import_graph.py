"""The house's import graph: every ``import`` of every servotune module, those inside functions
included (read with :mod:`ast`, nothing imported), checked for cycles and for imports of the
presentation layer (plots, figures, the report, the summaries, the command line) by the
numerics below it.

The graph as it stands has known faults, listed here each with what it is; the test fails on
any other (a new cycle or upward import) and on a listed one that is gone (so the list only
shrinks).
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "servotune"

#: Presentation: nothing below may import these.
PRESENTATION = ("servotune.plots", "servotune.regime_plots", "servotune.captions",
                "servotune.report", "servotune.summary", "servotune.cli",
                "servotune.measured.figures")

#: Known cycles (sorted module names): the ``.plot()`` methods of low-level results, the
#: contact kinds registered by the plant, the baseline called by the design job and using its
#: regime models.
KNOWN_CYCLES = {
    ("servotune.friction.equivalent", "servotune.friction.lugre", "servotune.plots",
     "servotune.twomass"),
}

#: Known upward imports (module, presentation module): ``.plot()`` methods of results, the
#: figures of an identification, a study's summary page and runner, the template's HTML.
KNOWN_UPWARD = {
    ("servotune.analysis", "servotune.plots"),
    ("servotune.chatter.sdm", "servotune.plots"),
    ("servotune.chatter.zoa", "servotune.plots"),
    ("servotune.design", "servotune.plots"),
    ("servotune.friction.lugre", "servotune.plots"),
    ("servotune.measured.ema", "servotune.measured.figures"),
    ("servotune.measured.update", "servotune.measured.figures"),
    ("servotune.simulate.result", "servotune.plots"),
    ("servotune.study.summary", "servotune.report"),
    ("servotune.template", "servotune.report"),
    ("servotune.twomass", "servotune.plots"),
}


def modules() -> dict:
    out = {}
    for path in ROOT.rglob("*.py"):
        if "__pycache__" in path.parts:
            continue
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


def import_graph() -> dict:
    """Module -> the servotune modules it imports (anywhere in its source)."""
    mods = modules()
    edges = {m: set() for m in mods}
    for name, path in mods.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text())):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[:len(package.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                targets = [f"{module}.{a.name}" if f"{module}.{a.name}" in mods else module
                           for a in node.names]
            for t in targets:
                while t not in mods and "." in t:
                    t = t.rsplit(".", 1)[0]
                if t in mods and t != name and t.startswith("servotune"):
                    edges[name].add(t)
    return edges


def cycles(edges: dict) -> set:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), set()
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.add(tuple(sorted(component)))

    for v in edges:
        if v not in index:
            visit(v)
    return out


def presentation(module: str) -> bool:
    return any(module == p or module.startswith(p + ".") for p in PRESENTATION)


def test_the_graph_sees_imports_inside_functions():
    """The study's description calls its checks from inside a function: that edge is in the
    graph (a reader of top-level imports only would miss it)."""
    edges = import_graph()
    assert "servotune.study.validate" in edges["servotune.study.spec"]
    assert "servotune.tuning.solve" in edges["servotune.tuning"]


def test_no_cycle_but_the_known_ones():
    found = cycles(import_graph())
    assert found - KNOWN_CYCLES == set(), "new import cycle(s)"
    assert KNOWN_CYCLES - found == set(), "a known cycle is gone: take it off the list"


def test_the_numerics_do_not_import_the_presentation_but_the_known_ones():
    edges = import_graph()
    upward = {(m, t) for m, targets in edges.items() if m != "servotune"
              and not presentation(m) for t in targets if presentation(t)}
    assert upward - KNOWN_UPWARD == set(), "new upward import(s)"
    assert KNOWN_UPWARD - upward == set(), "a known upward import is gone: take it off"
