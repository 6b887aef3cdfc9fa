"""The vtksvdag package's modules import without cycles: every ``import`` / ``from ... import`` of
a package module in the sources (at the top or inside a function) is an edge of the import graph,
and that graph must be acyclic; and each module imports on its own in a fresh interpreter."""
import ast
import pathlib
import subprocess
import sys

import pytest

import vtksvdag

PACKAGE = pathlib.Path(vtksvdag.__file__).resolve().parent


def package_modules():
    """{dotted module name: source path} of every .py file of the package."""
    modules = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        modules[".".join(parts)] = path
    return modules


def imported_modules(name, path, modules):
    """The package modules that the source of module ``name`` imports."""
    is_package = path.name == "__init__.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name in modules)
        elif isinstance(node, ast.ImportFrom):
            if node.level == 0:
                base = node.module or ""
            else:
                parts = name.split(".") if is_package else name.split(".")[:-1]
                parts = parts[: len(parts) - (node.level - 1)]
                base = ".".join(parts + ([node.module] if node.module else []))
            submodules = {f"{base}.{alias.name}" for alias in node.names} & set(modules)
            # `from . import stores` imports the submodule; the package itself is already loaded.
            if submodules and node.module is None:
                found |= submodules
            else:
                found |= submodules | ({base} & set(modules))
    found.discard(name)
    return found


def import_graph():
    modules = package_modules()
    return {name: imported_modules(name, path, modules) for name, path in modules.items()}


def find_cycle(graph):
    """One import cycle as a list of module names (first == last), or None."""
    state = {}  # 1: on the current path, 2: finished
    path = []

    def visit(node):
        state[node] = 1
        path.append(node)
        for target in sorted(graph[node]):
            if state.get(target) == 1:
                return path[path.index(target):] + [target]
            if target not in state:
                cycle = visit(target)
                if cycle:
                    return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def test_cycle_finder_finds_cycles():
    # The checker itself: a two-module and a three-module cycle are found, a DAG is not flagged.
    assert find_cycle({"a": {"b"}, "b": {"a"}}) in (["a", "b", "a"], ["b", "a", "b"])
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b", "c"}, "b": {"c"}, "c": set()}) is None


def test_graph_sees_function_level_and_relative_imports():
    graph = import_graph()
    # Known edges of the sources, at the top and inside functions, relative one and two levels up.
    assert "vtksvdag.volume" in graph["vtksvdag.fileio"]
    assert "vtksvdag.actor" in graph["vtksvdag.plotting"]  # inside add_segmentation
    assert "vtksvdag._svdagfile" in graph["vtksvdag.commands.compress"]  # from .._svdagfile
    assert "vtksvdag.stores" in graph["vtksvdag.distributed"]  # from . import stores


def test_package_imports_are_acyclic():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


@pytest.mark.parametrize("module", sorted(set(package_modules()) - {"vtksvdag.__main__"}))
def test_module_imports_alone(module):
    """Each module imports first in a fresh interpreter (no other module imported before it)."""
    result = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, result.stderr


def test_main_module_runs():
    # vtksvdag.__main__ runs the command line when imported: run it as `python -m vtksvdag`.
    result = subprocess.run([sys.executable, "-m", "vtksvdag", "--help"], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0 and "render" in result.stdout, result.stderr
