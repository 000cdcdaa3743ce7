"""The house a newcomer can live in (issue 34, house rule 14), as claims on the import graph and file sizes.

- no import cycle among the project's modules (imports inside functions count: a reader follows them too);
- no source file outside tests/ over 800 lines;
- a scenario author's read is a budget: the import closure of ``envs/pendulum.py`` (every project module it imports,
  directly or through others) stays within 3,000 lines and that of ``envs/heavy_top.py`` within 3,500;
- the contract side never imports the harness side: `rigidbench.contract`, `rigidbench.params`, the env base and
  the scenario modules reach neither the harness, the settings, the engines, the runner nor the CLI.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# Installed names -> folders of the repository (pyproject.toml's package-dir).
PACKAGES = {"rigidbench.envs": "envs", "rigidbench.analytic": "analytic", "rigidbench.models": "models"}
SOURCE_DIRS = ("rigidbench", "envs", "analytic", "benchmarks", "examples")
MAX_LINES = 800


def _path_of(module: str) -> Path | None:
    rel = None
    for prefix, folder in sorted(PACKAGES.items(), key=lambda kv: -len(kv[0])):
        if module == prefix or module.startswith(prefix + "."):
            rel = folder + module[len(prefix) :].replace(".", "/")
            break
    if rel is None and (module == "rigidbench" or module.startswith("rigidbench.")):
        rel = module.replace(".", "/")
    if rel is None:
        return None
    for candidate in (ROOT / f"{rel}.py", ROOT / rel / "__init__.py"):
        if candidate.exists():
            return candidate
    return None


def _module_of(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("").as_posix().removesuffix("/__init__")
    for prefix, folder in PACKAGES.items():
        if rel == folder or rel.startswith(folder + "/"):
            return prefix + rel[len(folder) :].replace("/", ".")
    return rel.replace("/", ".")


def _imports(path: Path) -> set[Path]:
    """Project modules `path` imports anywhere in its body (functions included)."""
    me = _module_of(path)
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1] + ([node.module] if node.module else []))
            names = [f"{base}.{a.name}" for a in node.names]
            names = [n if _path_of(n) else base for n in names]
        for name in names:
            target = _path_of(name)
            if target is not None and target != path:
                found.add(target)
    return found


def _project_modules() -> list[Path]:
    return sorted(p for d in ("rigidbench", "envs", "analytic") for p in (ROOT / d).rglob("*.py"))


def _closure(start: Path) -> set[Path]:
    seen, todo = set(), [start]
    while todo:
        p = todo.pop()
        if p not in seen:
            seen.add(p)
            todo.extend(_imports(p) - seen)
    return seen


def _lines(path: Path) -> int:
    return len(path.read_text().splitlines())


def test_no_import_cycle_among_the_project_modules():
    graph = {p: _imports(p) for p in _project_modules()}
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []

    def visit(v: Path) -> None:  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
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
                cycles.append(sorted(str(c.relative_to(ROOT)) for c in component))

    for v in graph:
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


def test_no_source_file_outside_tests_passes_800_lines():
    long = {
        str(p.relative_to(ROOT)): _lines(p)
        for d in SOURCE_DIRS
        for p in (ROOT / d).rglob("*.py")
        if _lines(p) > MAX_LINES
    }
    assert not long, f"split these by concern (house rule 14): {long}"


@pytest.mark.parametrize(("start", "budget"), [("envs/pendulum.py", 3000), ("envs/heavy_top.py", 3500)])
def test_a_scenarios_import_closure_stays_within_its_reading_budget(start, budget):
    closure = _closure(ROOT / start)
    total = sum(_lines(p) for p in closure)
    listing = ", ".join(f"{p.relative_to(ROOT)} {_lines(p)}" for p in sorted(closure))
    assert total <= budget, f"{start}: {total} lines in {len(closure)} files ({listing})"


HARNESS_SIDE = (
    "rigidbench/harness.py",
    "rigidbench/settings.py",
    "rigidbench/engines",
    "rigidbench/runner.py",
    "rigidbench/cli.py",
    "rigidbench/commands",
    "rigidbench/simulate.py",
)


@pytest.mark.parametrize(
    "module", ["rigidbench/contract.py", "rigidbench/params.py", "envs/base.py", "envs/pendulum.py"]
)
def test_the_contract_side_never_imports_the_harness_side(module):
    reached = {str(p.relative_to(ROOT)) for p in _closure(ROOT / module)}
    wrong = sorted(p for p in reached if p.startswith(HARNESS_SIDE))
    assert not wrong, f"{module} reaches {wrong}"
