"""Safe YAML loading for files from anywhere (:func:`safe_yaml`): no aliases, YAML 1.2 numbers, Aerialist's tags."""
from __future__ import annotations

import functools

from .errors import InvalidTestCase


def safe_yaml(text: str, name: str):
    """``yaml.safe_load`` for files from anywhere: no aliases (an alias bomb expands to gigabytes; Aerialist files
    have none), nesting too deep for the parser is an error, not a crash, and numbers read as YAML 1.2 reads them
    (``1e9`` is a number, not a string)."""
    import yaml

    try:
        if any(isinstance(token, yaml.AliasToken) for token in yaml.scan(text)):
            raise InvalidTestCase(f"{name}: YAML aliases (*name) are not supported")
        return yaml.load(text, Loader=_loader())
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark else ""
        raise InvalidTestCase(f"{name}: invalid YAML{where}") from None
    except RecursionError:
        raise InvalidTestCase(f"{name}: YAML nested too deeply") from None


#: The tag Aerialist master's ``to_yaml`` gives an assertion's variable (its Trajectory class), read as its name.
TRAJECTORY_TAG = "tag:yaml.org,2002:python/name:aerialist.px4.trajectory.Trajectory"


@functools.cache
def _loader():
    """A SafeLoader whose floats include exponents without a dot (``1e9``, ``-2E-3``), as in YAML 1.2, and that
    reads Aerialist master's tag of the trajectory variable as ``trajectory`` (no other Python tag)."""
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        pass

    exponent = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", exponent, list("-+0123456789"))
    Loader.add_constructor(TRAJECTORY_TAG, lambda loader, node: "trajectory")
    return Loader
