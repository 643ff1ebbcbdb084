"""A stand-in for ROS's bagpy: Aerialist master's file_helper imports ``bagreader`` for ROS ``.bag`` logs, which
``surrealist compete`` never writes (its flights are ULogs)."""


def bagreader(*args, **kwargs):
    """Raise ImportError: ROS .bag logs cannot be read under ``surrealist compete``."""
    raise ImportError("bagpy is a stand-in under surrealist compete: ROS .bag logs cannot be read")
