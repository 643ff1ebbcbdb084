"""The shape of the code and of the test tree.

The core of ``surrealist_gym`` (everything but the two applications ``competition/`` and ``fidelity/`` and the
command-line shell ``cli/``) imports neither application nor the sibling packages ``search`` and ``surrogates``; no
module is over 500 lines; no folder holds more than 15 modules. Imports point down the house's layers (:data:`LAYERS`),
no modules import each other round a cycle (imports inside functions and under ``TYPE_CHECKING`` count), no private
name is imported from another module, and one module decides which UAV flies. And pytest imports test modules by
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


def test_test_file_basenames_are_unique():
    names = Counter(path.name for path in Path(__file__).resolve().parent.rglob("test_*.py"))
    assert not [name for name, count in names.items() if count > 1]


# --- the house's arrows --------------------------------------------------------------------------------------------
#: The layers of the house, lowest first: a module imports only from its own layer or a lower one (the package's
#: __init__.py, the public face that re-exports, is above them all).
LAYERS = (
    ("errors",),
    ("testcase", "mission", "geometry", "trajectory", "metrics", "outcomes", "fitness"),
    ("sim",),
    ("logs", "aerialist", "store", "executors", "evaluation", "mutators", "results"),
    ("envs",),
    ("competition", "fidelity"),
    ("search", "surrogates"),
    ("cli",),
)
PACKAGES = ("surrealist_gym", "search", "surrogates")
MAX_MODULES_PER_FOLDER = 15


def all_modules() -> dict[str, Path]:
    """Dotted name -> file of every module of the three packages (a package by its __init__.py)."""
    found = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


def layer_of(module: str) -> int | None:
    parts = module.split(".")
    if parts[0] != "surrealist_gym":
        return LAYERS.index(("search", "surrogates"))
    matches = [(len(name.split(".")), i) for i, names in enumerate(LAYERS) for name in names
               if parts[1:1 + len(name.split("."))] == name.split(".")]
    return max(matches)[1] if matches else None


def module_arrows() -> list[tuple[str, int, str, str | None]]:
    """(importer, line, imported module, name imported from it or None) for every import between the packages'
    modules."""
    modules = all_modules()
    arrows = []
    for name, path in modules.items():
        for line, target in imported_modules(path):
            module, imported = target, None
            while module and module not in modules:
                module, _, imported = module.rpartition(".")[0], None, module.rpartition(".")[2]
            if module and module != name:
                arrows.append((name, line, module, imported))
    return arrows


def test_no_folder_of_the_package_holds_more_than_15_modules():
    folders = Counter(path.parent.relative_to(ROOT) for path in all_modules().values())
    crowded = [f"{folder}: {n} modules" for folder, n in sorted(folders.items()) if n > MAX_MODULES_PER_FOLDER]
    assert not crowded, "folders over 15 modules:\n" + "\n".join(crowded)


def test_imports_point_down():
    modules = all_modules()
    up = [f"{modules[a].relative_to(ROOT)}:{line}: {b}" for a, line, b, _ in module_arrows()
          if a != "surrealist_gym" and b != "surrealist_gym" and layer_of(a) is not None
          and layer_of(b) is not None and layer_of(b) > layer_of(a)]
    assert not up, "imports that run up:\n" + "\n".join(up)


def test_no_import_cycles():
    graph: dict[str, set[str]] = {}
    for a, _, b, _ in module_arrows():
        graph.setdefault(a, set()).add(b)
    cycles, index, low, stack, on_stack = [], {}, {}, [], set()

    def visit(v: str) -> None:  # Tarjan's strongly connected components
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
            while not component or component[-1] != v:
                component.append(stack.pop())
                on_stack.discard(component[-1])
            if len(component) > 1:
                cycles.append(" <-> ".join(sorted(component)))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert not cycles, "import cycles:\n" + "\n".join(cycles)


def test_no_private_name_is_imported_across_modules():
    modules = all_modules()
    private = [f"{modules[a].relative_to(ROOT)}:{line}: {b}.{name}" for a, line, b, name in module_arrows()
               if name and name.startswith("_") and not name.startswith("__")]
    assert not private, "private names imported from another module:\n" + "\n".join(private)


def test_one_module_decides_which_uav_flies():
    """Only sim/uav.py turns a UAV choice into a SimConfig or reads a test's uav.* settings: every command, env and
    report asks its decide_uav."""
    readers = ("resolve_uav", "load_profile", "default_profile", "profile_for_flight", "test_uav_settings",
               "with_uav_settings")
    allowed = {PACKAGE / "sim" / "uav.py", PACKAGE / "sim" / "profiles.py"}
    calls = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path in allowed:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call):
                name = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
                if name in readers or name == "sim_config":  # UavProfile.sim_config builds the SimConfig
                    calls.append(f"{path.relative_to(ROOT)}:{node.lineno}: {name}()")
    assert not calls, "a UAV decided outside sim/uav.py:\n" + "\n".join(calls)
    assert "def decide_uav(" in (PACKAGE / "sim" / "uav.py").read_text(encoding="utf-8")
