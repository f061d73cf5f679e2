"""The house's layering, checked by walking the imports and literals of the package.

    controllers ──signals──> couplings <──variables── plants / master / fmu
         │                      (the one place that knows both)
         └── kernel, signals, timebase, errors, validate, encoders, pulses

* controllers never import plants, the master, the FMU adapter, fmpy or the couplings, and never
  hold a plant variable name as a string;
* there is no import cycle in ``cosim``;
* the kernel and the trace load neither pandas nor the exporters (exports do);
* every controller offers the small ``Controller`` protocol.
"""

from __future__ import annotations

import ast
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import cosim
from cosim.controllers import Controller
from cosim.controllers.pmac import Pmac
from cosim.controllers.pokeys import PulseEngine
from cosim.controllers.trio import TrioController
from cosim.kernel import Simulation

PACKAGE = Path(cosim.__file__).resolve().parent
FMU_SRC = PACKAGE.parent / "fmu_src"
#: What a controller may import from cosim.
CONTROLLER_MAY_IMPORT = ("cosim.controllers", "cosim.kernel", "cosim.signals", "cosim.timebase", "cosim.errors",
                         "cosim.validate", "cosim.encoders", "cosim.pulses", "cosim.job")
#: Imported by controllers only for type annotations (never at run time).
CONTROLLER_MAY_TYPE_WITH = ("cosim.trace",)


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PACKAGE.rglob("*.py")}


def _resolve(module: str, name: str, modules: dict[str, Path]) -> str:
    """``from module import name``: the submodule if ``name`` is one, else the module."""
    return f"{module}.{name}" if f"{module}.{name}" in modules else module


def _imports(path: Path, modules: dict[str, Path]) -> tuple[set[str], set[str]]:
    """(run-time imports, type-checking-only imports) of a module, as module names."""
    tree = ast.parse(path.read_text())
    typing_only: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            typing_only.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    runtime, typing = set(), set()
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path).rpartition(".")[0]
    for node in ast.walk(tree):
        names: list[str] = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(parts + ([base] if base else []))
            names = [_resolve(base, a.name, modules) for a in node.names]
        (typing if id(node) in typing_only else runtime).update(names)
    return runtime, typing


def test_controllers_import_only_the_kernel_signals_time_base_errors_and_validation() -> None:
    modules = _modules()
    bad = []
    for name, path in modules.items():
        if not name.startswith("cosim.controllers"):
            continue
        runtime, typing = _imports(path, modules)
        for imported in runtime | typing:
            root = imported.split(".")[0]
            if root in ("fmpy", "pandas"):
                bad.append(f"{name} imports {imported}")
            elif root == "cosim":
                allowed = CONTROLLER_MAY_IMPORT + (CONTROLLER_MAY_TYPE_WITH if imported in typing else ())
                if imported != "cosim" and not imported.startswith(allowed):
                    bad.append(f"{name} imports {imported}")
    assert bad == []


def _plant_variable_names() -> set[str]:
    names = set()
    for toml in FMU_SRC.glob("*/model.toml"):
        names |= {v["name"] for v in tomllib.loads(toml.read_text())["variable"]}
    return names


def _code_strings(path: Path) -> list[tuple[int, str]]:
    """String literals of a module's code: not docstrings, not the constant pieces of f-strings."""
    tree = ast.parse(path.read_text())
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.JoinedStr):
            skip.update(id(v) for v in node.values)
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                skip.add(id(first.value))
    return [(n.lineno, n.value) for n in ast.walk(tree)
            if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in skip]


def test_no_controller_holds_a_plant_variable_name() -> None:
    variables = _plant_variable_names()
    assert {"step_rate", "pwm_on", "u_cmd", "encoder_count", "mark"} <= variables  # the walk reads the models
    found = [f"{name}:{line}: {text!r}" for name, path in _modules().items() if name.startswith("cosim.controllers")
             for line, text in _code_strings(path) if text in variables]
    assert found == []


def test_no_import_cycle_in_cosim() -> None:
    modules = _modules()
    graph = {name: {i for i in _imports(path, modules)[0] if i in modules and i != name}
             for name, path in modules.items()}
    # a package's __init__ re-exporting its submodules is not a cycle of concepts: drop package -> own child
    graph = {name: {i for i in deps if not i.startswith(name + ".")} for name, deps in graph.items()}
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for dep in sorted(graph[node]):
            if state.get(dep) == 1:
                cycles.append([*stack[stack.index(dep):], dep] if dep in stack else [node, dep])
            elif dep not in state:
                visit(dep, [*stack, dep])
        state[node] = 2

    for name in sorted(graph):
        if name not in state:
            visit(name, [name])
    assert cycles == []


@pytest.mark.parametrize("module", ["cosim.kernel", "cosim.trace", "cosim.master"])
def test_the_kernel_and_the_trace_load_neither_pandas_nor_the_exporters(module: str) -> None:
    heavy = ("pandas", "pyarrow", "cosim.export", "cosim.export_vcd", "cosim.export_wide")
    code = f"import sys, {module}; print(sorted(m for m in {heavy!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_every_controller_offers_its_outputs_and_inputs(sim: Simulation) -> None:
    controllers: list[Controller] = [PulseEngine(sim), TrioController(sim), Pmac(sim)]
    names = [sorted(s.name for s in c.outputs()) for c in controllers]
    assert "pokeys.x.step" in names[0] and "pokeys.z.dir" in names[0]
    assert {"trio.wdog", "trio.axis3.step", "trio.axis3.gate", "trio.axis3.pwm_mark"} <= set(names[1])
    assert names[2] == []  # no motors yet
    assert "pokeys.emergency" in {s.name for s in controllers[0].inputs()}


def test_nothing_in_cosim_imports_the_test_helpers_of_cosim_testing() -> None:
    modules = _modules()
    assert "cosim.testing" in modules  # the walk sees the package
    users = [name for name, path in modules.items() if not name.startswith("cosim.testing")
             for imported in set.union(*_imports(path, modules)) if imported.startswith("cosim.testing")]
    assert users == []
