"""The layout's rules (docs/architecture.md), checked on the source tree.

Imports are read with :mod:`ast`, every import statement counted wherever it sits
(inside functions too), except those under ``if TYPE_CHECKING:``.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("shared", "robot", "ground", "sim", "tools")
#: What each package may import of the project's packages (besides itself).
ALLOWED = {
    "shared": set(),
    "sim": {"shared"},
    "robot": {"shared"},
    "ground": {"shared"},
    "tools": {"shared", "sim", "robot", "ground"},
}
#: A subcommand module may import its own nested subcommand's module.
NESTED = {
    "tools.sim_cmd": {"tools.sim_serve_cmd"},
    "tools.memory_cmd": {"tools.memory_localize_cmd"},
    "tools.calibrate": {"tools.calibrate_equidistant_cmd", "tools.calibrate_capture_cmd"},
    "tools.vision_cmd": {"tools.vision_pair_cmd", "tools.vision_localize_cmd"},
    "tools.ground_cmd": {"tools.ground_memory_cmd", "tools.ground_teach_cmd",
                         "tools.ground_params_cmd", "tools.ground_keygen_cmd",
                         "tools.ground_stop_cmd", "tools.ground_goto_cmd",
                         "tools.ground_web_cmd"},
    "tools.bench_cmd": {"tools.bench_safety_cmd", "tools.bench_foxglove_cmd",
                        "tools.bench_web_cmd", "tools.bench_sweep_cmd"},
}
#: Lines a top-level tools/ module may have ("under ~200").
MAX_COMMAND_LINES = 210


def module_files() -> dict[str, Path]:
    """Every module of the packages, by dotted name."""
    files = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            files[name] = path
    return files


def _type_only_nodes(tree: ast.AST) -> set[int]:
    nodes = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            nodes.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    return nodes


def imports_of(path: Path, modules: dict[str, Path]) -> Iterator[tuple[int, str]]:
    """(line, module) of each project module ``path`` imports at run time."""
    tree = ast.parse(path.read_text())
    type_only = _type_only_nodes(tree)
    for node in ast.walk(tree):
        if id(node) in type_only:
            continue
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            targets = [f"{node.module}.{alias.name}" for alias in node.names]
            targets = [t if t in modules else node.module for t in targets]
        else:
            continue
        for target in targets:
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target:
                yield node.lineno, target


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    modules = module_files()
    return {name: {target for _, target in imports_of(path, modules) if target != name}
            for name, path in modules.items()}


def test_packages_import_only_what_the_rules_allow() -> None:
    modules = module_files()
    broken = []
    for name, path in modules.items():
        package = name.split(".")[0]
        for line, target in imports_of(path, modules):
            other = target.split(".")[0]
            if other != package and other not in ALLOWED[package]:
                broken.append(f"{path.relative_to(ROOT)}:{line} imports {target}")
    assert broken == []


def test_subcommand_modules_do_not_import_each_other() -> None:
    modules = module_files()
    commands = {name for name in modules if name.count(".") == 1 and name.startswith("tools.")}
    broken = []
    for name in commands - {"tools.cli"}:
        for line, target in imports_of(modules[name], modules):
            if target in commands and target not in NESTED.get(name, set()):
                broken.append(f"{name}:{line} imports {target}")
    assert broken == []


def test_no_import_cycle(graph: dict[str, set[str]]) -> None:
    # Tarjan's strongly connected components; a component of two or more is a cycle.
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert cycles == []


def test_the_top_level_of_tools_is_thin() -> None:
    long = {path.name: n for path in (ROOT / "tools").glob("*.py")
            if (n := len(path.read_text().splitlines())) > MAX_COMMAND_LINES}
    assert long == {}
