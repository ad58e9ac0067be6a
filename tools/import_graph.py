"""The import graph of splinekit, exporters and models, read from the source with ``ast``.

Usage::

    python tools/import_graph.py             # summary: cycles, upward imports, in-function imports
    python tools/import_graph.py --dot g.dot # the graph between layers in Graphviz format
    python tools/import_graph.py --png g.png # the same drawn with matplotlib

Every module is placed in a layer of the list below (the layer order of the design notes:
imports run one way, down the list); an import from a module to a module of a later layer is an
*upward* import. Imports inside functions are listed apart: they are meant for optional heavy
backends only (OCP, manifold3d, numba, the optional extras).
"""

from __future__ import annotations

import argparse
import ast
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("splinekit", "exporters", "models")

# Layers in import order: a module may import from its own layer and from layers above it.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("base", ("splinekit.errors", "splinekit._validate", "splinekit.tolerances", "splinekit.limits",
              "splinekit._atomic", "splinekit._progress", "splinekit._signals", "splinekit._kernels",
              "splinekit._siblings", "splinekit._registry")),
    ("basis", ("splinekit.basis",)),
    ("curves/surfaces", ("splinekit.curves", "splinekit.surfaces")),
    ("construct/fit/project", ("splinekit.construct", "splinekit.fit", "splinekit.closest")),
    ("diffgeom", ("splinekit.diffgeom",)),
    ("brep", ("splinekit.brep",)),
    ("mesh", ("splinekit.mesh",)),
    ("subdiv", ("splinekit.subdiv",)),
    ("implicit/pointcloud", ("splinekit.implicit", "splinekit.pointcloud", "splinekit.levelset")),
    ("tessellation", ("splinekit.tessellation",)),
    ("convert/analysis/plot", ("splinekit.convert", "splinekit.analysis", "splinekit.plot")),
    ("interop", ("splinekit.interop",)),
    ("optional", ("splinekit.neural", "splinekit.batch", "splinekit.comparison")),
    ("package", ("splinekit",)),
    ("exporters", ("exporters",)),
    ("models", ("models",)),
    # the command line is the application on top: it maps arguments to models and exporters
    ("cli", ("splinekit.cli", "splinekit.__main__")),
)

MAX_LINES = 520
"""A module longer than this (about 500 lines) holds more than one thing: split it along what it holds."""

# Packages whose import inside a function is legitimate: heavy or optional backends.
OPTIONAL_BACKENDS = ("OCP", "build123d", "cadquery", "manifold3d", "numba", "triangle", "matplotlib",
                     "jax", "optax", "torch", "dask", "distributed", "pandas", "pyarrow", "trimesh", "lxml",
                     "defusedxml", "PIL")


def layer_of(module: str) -> int:
    """Index in LAYERS of the longest prefix matching ``module`` (-1: outside the project)."""
    best, best_len = -1, -1
    for index, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = index, len(prefix)
    return best


@dataclass
class Graph:
    modules: dict[str, Path] = field(default_factory=dict)
    top: dict[str, set[str]] = field(default_factory=dict)          # module-level imports
    inner: dict[str, list[tuple[str, int]]] = field(default_factory=dict)  # in-function imports (target, line)


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _targets(module: str, is_package: bool, node, known: set[str]) -> list[str]:
    """Project modules (or external top-level packages) an import statement refers to."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    base = _resolve(module, is_package, node)
    out = []
    for alias in node.names:
        candidate = f"{base}.{alias.name}" if base else alias.name
        out.append(candidate if candidate in known else base)
    return out


def _in_type_checking(parents: list[ast.AST]) -> bool:
    return any(isinstance(p, ast.If) and "TYPE_CHECKING" in ast.unparse(p.test) for p in parents)


def build(root: Path = ROOT, packages: tuple[str, ...] = PACKAGES) -> Graph:
    """The import graph of the packages ``packages`` found under the folder ``root``."""
    g = Graph()
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            g.modules[_module_name(path, root)] = path
    known = set(g.modules)
    for module, path in g.modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        is_package = path.name == "__init__.py"
        g.top[module], g.inner[module] = set(), []
        stack: list[tuple[ast.AST, list[ast.AST]]] = [(tree, [])]
        while stack:
            node, parents = stack.pop()
            for child in ast.iter_child_nodes(node):
                stack.append((child, parents + [node]))
            if not isinstance(node, (ast.Import, ast.ImportFrom)) or _in_type_checking(parents):
                continue
            in_function = any(isinstance(p, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)) for p in parents)
            for target in _targets(module, is_package, node, known):
                if in_function:
                    g.inner[module].append((target, node.lineno))
                elif target.split(".")[0] in PACKAGES and target != module:
                    g.top[module].add(target)
    return g


def _project_target(target: str, known: set[str]) -> str | None:
    """The project module an import names (walking up to a known module), or None."""
    while target and target not in known:
        target = target.rpartition(".")[0]
    return target or None


def _all_targets(g: Graph, module: str) -> set[str]:
    """Project modules ``module`` imports, at module level or inside functions."""
    known = set(g.modules)
    names = set(g.top[module]) | {t for t, _ in g.inner[module]}
    return {t for t in (_project_target(x, known) for x in names if x.split(".")[0] in PACKAGES)
            if t and t != module and not t.startswith(module + ".")}


def cycles(g: Graph) -> list[list[str]]:
    """Strongly connected components of more than one module, counting imports inside functions
    too (an import deferred into a function still makes a circle; Tarjan's algorithm, iterative).
    A package importing its own submodules is not a circle."""
    edges = {m: _all_targets(g, m) for m in g.modules}
    index, low, on_stack, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in g.modules:
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter[0]; counter[0] += 1
        stack.append(root); on_stack.add(root)
        while work:
            node, it = work[-1]
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter[0]; counter[0] += 1
                    stack.append(nxt); on_stack.add(nxt)
                    work.append((nxt, iter(sorted(edges[nxt]))))
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    comp = []
                    while True:
                        w = stack.pop(); on_stack.discard(w); comp.append(w)
                        if w == node:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return out


def upward(g: Graph) -> list[tuple[str, str]]:
    """Imports (module level or inside functions) from a layer to a later layer."""
    return sorted((m, t) for m in g.modules for t in _all_targets(g, m) if layer_of(t) > layer_of(m))


def inner_project_imports(g: Graph) -> list[tuple[str, str, int]]:
    """In-function imports of project modules (module, target, line), one row per statement."""
    return sorted({(m, t, line) for m, items in g.inner.items() for t, line in items if t.split(".")[0] in PACKAGES})


def long_modules(g: Graph, limit: int = MAX_LINES) -> list[tuple[str, int]]:
    """Modules with more than ``limit`` lines, longest first."""
    sizes = ((m, len(p.read_text(encoding="utf-8").splitlines())) for m, p in g.modules.items())
    return sorted(((m, n) for m, n in sizes if n > limit), key=lambda item: -item[1])


def layer_edges(g: Graph) -> dict[tuple[str, str], int]:
    """Counts of module-level imports between distinct layers."""
    known = set(g.modules)
    counts: dict[tuple[str, str], int] = {}
    for module, targets in g.top.items():
        for t in targets:
            target = _project_target(t, known)
            if target is None:
                continue
            a, b = layer_of(module), layer_of(target)
            if a != b and a >= 0 and b >= 0:
                key = (LAYERS[a][0], LAYERS[b][0])
                counts[key] = counts.get(key, 0) + 1
    return counts


def to_dot(g: Graph) -> str:
    lines = ["digraph splinekit {", "  rankdir=TB;"]
    for name, _ in LAYERS:
        lines.append(f'  "{name}";')
    for (a, b), n in sorted(layer_edges(g).items()):
        up = [x for x, _ in LAYERS].index(b) > [x for x, _ in LAYERS].index(a)
        lines.append(f'  "{a}" -> "{b}" [label="{n}"{", color=red" if up else ""}];')
    lines.append("}")
    return "\n".join(lines)


def draw_png(g: Graph, path: str) -> None:
    """Layers top to bottom; an arrow from importer to imported (red when it imports a later layer)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [n for n, _ in LAYERS]
    y = {n: -i for i, n in enumerate(names)}
    fig, ax = plt.subplots(figsize=(7, 10))
    for n in names:
        ax.text(0, y[n], n, ha="center", va="center", bbox=dict(boxstyle="round", fc="#eef", ec="#669"))
    for (a, b), count in layer_edges(g).items():
        bad = names.index(b) > names.index(a)
        offset = 0.35 if bad else -0.35
        ax.annotate("", xy=(offset, y[b]), xytext=(offset, y[a]),
                    arrowprops=dict(arrowstyle="->", color="red" if bad else "#888", lw=0.6,
                                    connectionstyle=f"arc3,rad={0.25 if bad else -0.25}"))
    ax.set_xlim(-2, 2)
    ax.set_ylim(-len(names), 1)
    ax.axis("off")
    ax.set_title("splinekit import graph between layers (red: upward)")
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dot", help="write the layer graph in Graphviz format")
    parser.add_argument("--png", help="draw the layer graph as a PNG")
    args = parser.parse_args(argv)
    g = build()
    cyc, up, inner = cycles(g), upward(g), inner_project_imports(g)
    print(f"{len(g.modules)} modules")
    print(f"import circles: {len(cyc)}")
    for c in cyc:
        print("  " + " <-> ".join(c))
    print(f"upward imports: {len(up)}")
    for a, b in up:
        print(f"  {a} -> {b}")
    print(f"in-function imports of project modules: {len(inner)}")
    for a, b, line in inner:
        print(f"  {a}:{line} -> {b}")
    long = long_modules(g)
    print(f"modules over {MAX_LINES} lines: {len(long)}")
    for m, n in long:
        print(f"  {m}: {n}")
    if args.dot:
        Path(args.dot).write_text(to_dot(g) + "\n", encoding="utf-8")
    if args.png:
        draw_png(g, args.png)
    return 1 if (cyc or up or inner or long) else 0


if __name__ == "__main__":
    sys.exit(main())
