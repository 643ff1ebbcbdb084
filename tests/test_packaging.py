"""The three packages ship their type annotations: a py.typed marker (PEP 561) each, declared as package data, so the
wheel holds it (checked by building one: ``pip wheel . --no-deps``)."""
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python 3.11+

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("surrealist_gym", "search", "surrogates")


def test_every_package_ships_py_typed():
    package_data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    for package in PACKAGES:
        assert (ROOT / package / "__init__.py").is_file() and (ROOT / package / "py.typed").is_file()
        assert "py.typed" in package_data.get(package, []), f"{package}: py.typed is not package data"
