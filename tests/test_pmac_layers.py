"""The PMAC language front end imports one way: text -> syntax tree -> program -> runtime -> machine (issue 27).

Type-only imports (under ``TYPE_CHECKING``) count too: a circle of them is still a circle of concepts.
The layers, lowest first; a module may import its own layer and those below, never one above:
"""

from __future__ import annotations

import ast
from pathlib import Path

import cosim.controllers.pmac as package

LAYERS = [
    # foundations: numbers, time, moves, encoders, the table, coordinate systems, motors
    {"units", "arith", "pieces", "profile", "paths", "motion", "runner", "encoder", "ect", "coord", "servo", "motor",
     "ivartable"},
    {"source", "preprocess"},  # text
    {"grammar", "nodes", "syntax"},  # syntax tree
    {"program", "setupfile"},  # program
    {"bus", "mvars", "evaluate", "interpreter", "commands", "runtime"},  # runtime
    {"machine", "ports"},  # the controller and its connectors
]


def _imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("cosim.controllers.pmac"):
            names.add(node.module.rpartition(".")[2] if node.module != "cosim.controllers.pmac" else "")
            if node.module == "cosim.controllers.pmac":
                names.update(alias.name for alias in node.names)
    return names - {""}


def _layer(module: str) -> int:
    return next(i for i, layer in enumerate(LAYERS) if module in layer)


def test_every_module_has_a_layer() -> None:
    modules = {p.stem for p in Path(package.__file__).parent.glob("*.py")} - {"__init__"}
    assert modules == set().union(*LAYERS)


def test_no_module_imports_a_layer_above_its_own() -> None:
    bad = []
    for path in Path(package.__file__).parent.glob("*.py"):
        if path.stem == "__init__":
            continue
        for imported in _imports(path):
            if _layer(imported) > _layer(path.stem):
                bad.append(f"{path.stem} imports {imported}")
    assert bad == []


def test_interpreter_machine_mvars_and_runtime_import_each_other_in_no_circle() -> None:
    """Within the runtime layer the order is bus -> mvars -> evaluate -> interpreter -> commands -> runtime."""
    rank = {name: i for i, name in enumerate(["bus", "mvars", "evaluate", "interpreter", "commands", "runtime"])}
    folder = Path(package.__file__).parent
    bad = [f"{name} imports {imported}" for name in rank for imported in _imports(folder / f"{name}.py")
           if imported in rank and rank[imported] >= rank[name]]
    assert bad == []
    assert "machine" not in set().union(*(_imports(folder / f"{name}.py") for name in rank))
