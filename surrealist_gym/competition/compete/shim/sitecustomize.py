"""Run at the tool's interpreter start (``surrealist compete`` puts this folder first on ``PYTHONPATH``): make every
Aerialist agent fly surrealist-gym's simulator and seed the tool's global random generators
(:mod:`surrealist_compete_shim`), then run the ``sitecustomize`` this one shadows, if any."""
import importlib.machinery
import importlib.util
import os
import sys

import surrealist_compete_shim

surrealist_compete_shim.install()
surrealist_compete_shim.seed_generators()


def _shadowed() -> None:
    here = os.path.dirname(os.path.abspath(__file__))
    rest = [p for p in sys.path if os.path.abspath(p or os.curdir) != here]
    spec = importlib.machinery.PathFinder.find_spec("sitecustomize", rest)
    if spec is not None and spec.loader is not None:
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)


_shadowed()
