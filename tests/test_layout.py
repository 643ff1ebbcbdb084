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
