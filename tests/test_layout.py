"""The shape of the code and of the test tree.

The core of ``surrealist_gym`` (everything but the two applications ``competition/`` and ``fidelity/`` and the
command-line shell ``cli/``) imports neither application nor the sibling packages ``search`` and ``surrogates``; no
module is over 500 lines; the package's top level holds at most 15 modules. And pytest imports test modules by
basename (tests/ has no __init__.py), so two test files with one name in different folders break collection of the
whole suite.
"""
import ast
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "surrealist_gym"
NOT_CORE = ("competition", "fidelity", "cli")  # folders of surrealist_gym/ outside the core
OUT_OF_CORE = ("surrealist_gym.competition", "surrealist_gym.fidelity", "search", "surrogates")
MAX_LINES = 500
MAX_TOP_LEVEL = 15


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """Every module an import statement of the file reaches (line, dotted name), at any depth (inside functions
    too), relative imports resolved; ``from a import b`` reaches both ``a`` and ``a.b`` (b may be a module)."""
    package = list(path.relative_to(ROOT).parent.parts)  # what a relative import starts from, __init__.py too
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[:len(package) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module
            found.append((node.lineno, module))
            found += [(node.lineno, f"{module}.{alias.name}") for alias in node.names if alias.name != "*"]
    return found


def core_modules() -> list[Path]:
    return sorted(p for p in PACKAGE.rglob("*.py") if p.relative_to(PACKAGE).parts[0] not in NOT_CORE)


def _reaches(module: str, target: str) -> bool:
    return module == target or module.startswith(target + ".")


def test_the_core_imports_neither_application_nor_search_nor_surrogates():
    assert len(core_modules()) > 30  # the walk found the package
    arrows = [f"{path.relative_to(ROOT)}:{line}: {module}" for path in core_modules()
              for line, module in imported_modules(path) if any(_reaches(module, t) for t in OUT_OF_CORE)]
    assert not arrows, "the core imports out of the core:\n" + "\n".join(arrows)


def test_no_module_is_over_500_lines():
    long = [f"{path.relative_to(ROOT)}: {n} lines" for folder in ("surrealist_gym", "search", "surrogates")
            for path in sorted((ROOT / folder).rglob("*.py"))
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > MAX_LINES]
    assert not long, f"modules over {MAX_LINES} lines:\n" + "\n".join(long)


def test_the_package_top_level_holds_at_most_15_modules():
    top = sorted(path.name for path in PACKAGE.glob("*.py"))
    assert "__init__.py" in top and len(top) <= MAX_TOP_LEVEL, f"{len(top)} modules in surrealist_gym/: {top}"


def test_test_file_basenames_are_unique():
    names = Counter(path.name for path in Path(__file__).resolve().parent.rglob("test_*.py"))
    assert not [name for name, count in names.items() if count > 1]


SIM = PACKAGE / "sim"
MAX_FOLDER = 15  # modules per folder of the simulator, __init__.py included
ABOVE_SIM = ("surrealist_gym.logs", "surrealist_gym.cli", "surrealist_gym.envs", "surrealist_gym.executors",
             "surrealist_gym.evaluation", "surrealist_gym.results", "surrealist_gym.store", "surrealist_gym.mutators",
             "surrealist_gym.fitness")
BELOW_SIM = ("testcase.py", "mission.py", "geometry.py", "trajectory.py", "errors.py", "outcomes.py")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def test_no_folder_of_the_simulator_holds_more_than_15_modules():
    folders = {path.parent for path in SIM.rglob("*.py")}
    full = {str(f.relative_to(ROOT)): n for f in folders if (n := len(list(f.glob("*.py")))) > MAX_FOLDER}
    assert not full, f"folders over {MAX_FOLDER} modules: {full}"


def test_the_simulator_modules_import_no_cycle():
    modules = {_module_name(path): path for path in SIM.rglob("*.py")}
    edges = {name: sorted({m for _, m in imported_modules(path) if m in modules and m != name})
             for name, path in modules.items()}
    done, on_path = set(), []

    def visit(name):  # depth-first; a module met again on the current path closes a cycle
        if name in on_path:
            raise AssertionError("import cycle: " + " -> ".join(on_path[on_path.index(name):] + [name]))
        if name in done:
            return
        on_path.append(name)
        for other in edges[name]:
            visit(other)
        on_path.pop()
        done.add(name)

    for name in sorted(modules):
        visit(name)


def test_the_simulator_imports_nothing_above_it_and_the_values_import_no_simulator():
    up = [f"{path.relative_to(ROOT)}:{line}: {module}" for path in sorted(SIM.rglob("*.py"))
          for line, module in imported_modules(path) if any(_reaches(module, t) for t in ABOVE_SIM)]
    down = [f"{name}:{line}: {module}" for name in BELOW_SIM for line, module in imported_modules(PACKAGE / name)
            if _reaches(module, "surrealist_gym.sim")]
    assert not up and not down, "\n".join(up + down)
