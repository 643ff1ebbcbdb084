"""Modules put first on a competition tool's ``PYTHONPATH`` by ``surrealist compete`` (never imported from here, but
``surrealist_compete_wire``, the JSON wire the server shares).

``sitecustomize`` installs :mod:`surrealist_compete_shim` at interpreter start; ``bagpy`` stands in for ROS's bagpy,
which Aerialist master's ``file_helper`` imports for ``.bag`` logs only. All of them use the standard library alone,
so the tool may run in any Python environment that holds Aerialist's own imports.
"""
