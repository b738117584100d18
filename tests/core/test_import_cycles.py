"""No import cycle among spflow's modules, counting imports inside functions too (a lazy import hides a cycle from
the interpreter, not from a reader): the module graph, built from the source, must be acyclic."""

import ast
from pathlib import Path

import networkx as nx

import spflow

PACKAGE = Path(spflow.__file__).parent


def _module_name(path: Path, package: Path) -> str:
    parts = path.relative_to(package.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph(package: Path = PACKAGE) -> nx.DiGraph:
    """Edges ``a -> b``: module ``a`` imports module ``b`` (anywhere in its source). ``from pkg import sub`` is an
    edge to the submodule ``pkg.sub`` only, since that import does not need ``pkg``'s own names."""
    paths = {_module_name(p, package): p for p in package.rglob("*.py")}
    graph = nx.DiGraph()
    graph.add_nodes_from(paths)
    for name, path in paths.items():
        package_name = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package_name.split(".")[: len(package_name.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module
                submodules = [f"{module}.{a.name}" for a in node.names if f"{module}.{a.name}" in paths]
                targets = submodules if len(submodules) == len(node.names) else [module, *submodules]
            else:
                continue
            graph.add_edges_from((name, t) for t in targets if t in paths and t != name)
    return graph


def test_the_import_graph_is_seen():
    """The graph is not vacuous: known edges are in it (a module-level and a function-level import)."""
    graph = import_graph()
    assert graph.has_edge("spflow.plugins.forward.simulate", "spflow.plugins.forward.run_arguments")
    assert graph.has_edge("spflow.plugins.surrogates.contract", "spflow.core.plugins")
    assert graph.number_of_edges() > 300


def test_no_import_cycle_among_spflow_modules():
    cycles = [sorted(c) for c in nx.strongly_connected_components(import_graph()) if len(c) > 1]
    assert cycles == []


def test_a_planted_cycle_is_found(tmp_path):
    pkg = tmp_path / "toy"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from . import b\n")
    (pkg / "b.py").write_text("def f():\n    from toy.a import g\n")
    cycles = [sorted(c) for c in nx.strongly_connected_components(import_graph(pkg)) if len(c) > 1]
    assert cycles == [["toy.a", "toy.b"]]
