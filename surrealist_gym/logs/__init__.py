"""Flight logs: PX4 ULog (pyulog), MAVLink telemetry logs and ArduPilot DataFlash logs (pymavlink).

:func:`read_flight` picks the reader from the file's first bytes (else its extension) and returns an immutable
:class:`FlightLog`. :func:`write_run_ulog` writes a simulated run as a ULog that the same reader loads
(:func:`write_ulog`: any local-position samples).

Example::

    import surrealist_gym as sg
    flight = sg.read_flight("case0.ulg")
    flight.trajectory                          # the paper's pipeline (86 points for case0)
"""
from __future__ import annotations

import os
import struct

from ..errors import LogFormatError, one_line, regular_file
from .flight import FlightLog, LocalPositions, ModeSpan
from .mavlink import DATAFLASH_MAGIC, MAVLINK_STX, read_dataflash, read_tlog
from .ulog import ULOG_MAGIC, read_ulog
from .ulog_writer import write_run_ulog, write_ulog

_EXTENSIONS = {".ulg": "ulog", ".tlog": "tlog", ".mav": "tlog", ".bin": "dataflash"}


def detect_format(path) -> str | None:
    """``"ulog"``, ``"tlog"`` or ``"dataflash"`` from the first bytes of the file, else from its extension."""
    name = regular_file(path, "log file", LogFormatError)
    try:
        with open(name, "rb") as f:
            head = f.read(16)
    except OSError as err:
        raise LogFormatError(f"{name}: cannot read log file ({err.strerror or err})") from err
    if head.startswith(ULOG_MAGIC):
        return "ulog"
    if head.startswith(DATAFLASH_MAGIC):
        return "dataflash"
    if len(head) > 8 and head[8] in MAVLINK_STX:  # 8-byte timestamp, then a MAVLink frame
        return "tlog"
    return _EXTENSIONS.get(os.path.splitext(name)[1].lower())


def read_flight(path) -> FlightLog:
    """Read a flight log (.ulg, .tlog, .bin) into a :class:`FlightLog`.

    Args:
        path: the log file (str or PathLike), or a binary file holding a ULog.

    Raises:
        LogFormatError: unknown format, unreadable, corrupt, or no valid position (one line naming the file).
    """
    if hasattr(path, "read"):
        return read_ulog(path)  # pymavlink reads files by name only
    name = os.fspath(path)
    fmt = detect_format(name)
    readers = {"ulog": read_ulog, "tlog": read_tlog, "dataflash": read_dataflash}
    if fmt not in readers:
        raise LogFormatError(f"{name}: unknown log format (expected a PX4 ULog .ulg, a MAVLink .tlog "
                             f"or an ArduPilot DataFlash .bin)")
    try:
        return readers[fmt](name)
    except (AttributeError, KeyError, IndexError, TypeError, ValueError, OverflowError, struct.error) as err:
        # damaged message definitions decode into messages without the fields their type promises
        raise LogFormatError(f"{name}: corrupt {fmt} log ({type(err).__name__}: {one_line(err)})") from None


__all__ = ["FlightLog", "LocalPositions", "ModeSpan", "detect_format", "read_flight", "read_ulog", "write_run_ulog",
           "write_ulog"]
