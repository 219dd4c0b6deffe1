"""The layout keeps its promises: no import loops, small modules, a public facade, fast start-up."""

from __future__ import annotations

import ast
import gc
import re
import subprocess
import sys
from pathlib import Path

import rtde_spec

from .helpers import ROOT

PACKAGE = ROOT / "rtde_spec"
MAX_LINES = 400


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph() -> dict[str, set[str]]:
    """Module -> modules it imports, function-level and TYPE_CHECKING imports included.

    Collected garbage first and none while parsing: a finalizer an earlier test left (an event
    loop's __del__) running inside CPython 3.11's AST construction raises SystemError there."""
    gc.collect()
    gc.disable()
    try:
        return _import_graph()
    finally:
        gc.enable()


def _import_graph() -> dict[str, set[str]]:
    modules = {module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join([*parts, base] if base else parts)
                targets = [base, *(f"{base}.{a.name}" for a in node.names)]
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name and not name.startswith(target + ".") and target != "rtde_spec":
                    graph[name].add(target)
    return graph


def test_no_import_cycles() -> None:
    graph = import_graph()
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                cycles.append([*stack[stack.index(nxt) :], nxt])
            elif nxt not in state:
                visit(nxt, [*stack, nxt])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    assert not cycles, cycles


def test_generated_code_is_imported_only_by_the_layer_above() -> None:
    graph = import_graph()
    for name, targets in graph.items():
        if name.startswith("rtde_spec._generated"):
            continue
        for target in targets:
            if target.startswith("rtde_spec._generated"):
                assert not name.startswith("rtde_spec.cli.") or target.endswith("constants"), (name, target)


def test_no_hand_written_module_is_over_400_lines() -> None:
    for path in PACKAGE.rglob("*.py"):
        if "_generated" in path.parts:
            continue
        lines = len(path.read_text().splitlines())
        assert lines <= MAX_LINES, f"{path.relative_to(ROOT)}: {lines} lines"


def test_readme_imports_only_public_names() -> None:
    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", readme, re.S)
    assert blocks
    for block in blocks:
        assert "_generated" not in block
        for module in re.findall(r"^\s*from ([\w.]+) import", block, re.M):
            assert module.startswith("rtde_spec"), module
    for name in rtde_spec.__all__:
        assert getattr(rtde_spec, name) is not None


def test_start_up_does_not_load_pydantic_or_construct() -> None:
    code = (
        "import sys\nfrom rtde_spec import RecipeCodec\n"
        "RecipeCodec.for_names(['timestamp', 'actual_q'], 'output')\n"
        "import rtde_spec.cli.main\nrtde_spec.cli.main.build_parser()\n"
        "print(sorted(m for m in ('pydantic', 'construct', 'numpy', 'pyarrow') if m in sys.modules))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"


EMULATOR_FLOORS = ("server", "ports", "controller", "urscript", "arm")


def test_the_emulator_reads_down_from_server_to_arm() -> None:
    """server → ports → controller → urscript → arm: a wing imports only the wings below it."""
    graph = import_graph()

    def floor(module: str) -> int | None:
        parts = module.split(".")
        if len(parts) < 3 or parts[:2] != ["rtde_spec", "emulator"]:
            return None
        return EMULATOR_FLOORS.index(parts[2]) if parts[2] in EMULATOR_FLOORS else None

    modules = [m for m in graph if m.startswith("rtde_spec.emulator.")]
    assert {m.split(".")[2] for m in modules} <= set(EMULATOR_FLOORS), "a module outside the wings"
    upward = [
        (name, target)
        for name in modules
        for target in graph[name]
        if (a := floor(name)) is not None and (b := floor(target)) is not None and b < a
    ]
    assert not upward, upward


def test_the_document_importers_serve_only_the_cli() -> None:
    """Run time never loads the importers: only `rtde-spec spec import` reads UR's documents."""
    graph = import_graph()
    users = {
        name
        for name, targets in graph.items()
        if any(t.startswith("rtde_spec.importers") for t in targets)
        and not name.startswith("rtde_spec.importers")
    }
    assert users and all(name.startswith("rtde_spec.cli.") for name in users), users


# The floors, bottom up (docs/architecture.md draws them): a module imports only its own floor and
# the floors below. Leaves import nothing of the package; the generated constants are pure data.
FLOORS: tuple[tuple[str, ...], ...] = (
    ("rtde_spec.errors", "rtde_spec.printable", "rtde_spec.endpoints", "rtde_spec._generated.constants"),
    ("rtde_spec.wire",),
    ("rtde_spec._generated",),
    ("rtde_spec.metamodel",),
    ("rtde_spec.output",),
    ("rtde_spec.recipes", "rtde_spec.realtime", "rtde_spec.external", "rtde_spec.primary"),
    ("rtde_spec.rtde",),
    ("rtde_spec.capture", "rtde_spec.emulator", "rtde_spec.importers", "rtde_spec.examples"),
    ("rtde_spec.cli",),
    ("rtde_spec", "rtde_spec.__main__"),
)
# The one lazy lookup back up: the RTDE layouts are compiled, on first use, from the generated
# spec data (wire/rtde_layouts.py), so the engine needs no pydantic meta-model at run time.
LOOKUPS_UP = {("rtde_spec.wire.rtde_layouts", "rtde_spec._generated.spec_data")}


def floor_of(module: str) -> int:
    best, length = -1, -1
    for index, members in enumerate(FLOORS):
        for member in members:
            if (module == member or module.startswith(member + ".")) and len(member) > length:
                best, length = index, len(member)
    assert best >= 0, f"{module} is on no floor: add it to FLOORS and docs/architecture.md"
    return best


def arrows_up() -> set[tuple[str, str]]:
    graph = import_graph()
    return {
        (name, target)
        for name, targets in graph.items()
        for target in targets
        if floor_of(target) > floor_of(name)
    }


def test_imports_run_down_the_floors() -> None:
    """No new arrow back up: generated code extends only wire/, wire/ names nothing above it."""
    assert arrows_up() == LOOKUPS_UP


def test_the_floors_diagram_is_the_one_the_imports_draw() -> None:
    from tests.floors import DOC, block, diagram

    assert block(DOC.read_text()) == diagram(), "run python -m tests.floors and commit docs/architecture.md"


def test_no_function_in_cli_or_capture_is_long() -> None:
    """About 60 lines at most (an argument parser's list of options may run a little over)."""
    long = []
    for folder in ("cli", "capture"):
        for path in (PACKAGE / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                    lines = (node.end_lineno or node.lineno) - node.lineno + 1
                    if lines > (70 if node.name == "add_parser" else 60):
                        long.append(f"{path.relative_to(ROOT)}:{node.name} {lines} lines")
    assert not long, long
