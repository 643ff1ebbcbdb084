"""The test tree's shape: pytest imports test modules by basename (tests/ has no __init__.py), so two test files
with one name in different folders break collection of the whole suite."""
from collections import Counter
from pathlib import Path


def test_test_file_basenames_are_unique():
    names = Counter(path.name for path in Path(__file__).resolve().parent.rglob("test_*.py"))
    assert not [name for name, count in names.items() if count > 1]
