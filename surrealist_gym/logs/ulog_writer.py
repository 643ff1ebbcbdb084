"""Write a simulated run as a minimal PX4 ULog that pyulog and :func:`~surrealist_gym.logs.read_flight` load.

Written from the public ULog file-format specification (docs.px4.io, "ULog File Format"): a 16-byte header
(magic, version 1, start timestamp), a flag-bits message ``B``, then the definitions (formats ``F``, infos ``I``,
parameters ``P``), then subscriptions ``A`` and data ``D`` messages. Every message is ``uint16 size, uint8 type,
payload``, little-endian and packed. pyulog's own ``ULog.write_ulog`` only re-serialises a log that pyulog has
parsed (its state lives in private attributes), so it cannot build one from arrays.

Topics written: ``vehicle_local_position`` (NED, as PX4 logs it), ``vehicle_status`` (one nav_state for the whole
run), and when a home or mission is known ``home_position``, ``mission`` and ``navigator_mission_item``.
"""
from __future__ import annotations

import os
import struct
from typing import Mapping

import numpy as np

from ..mission import Command, Mission, local_to_geo
from .ulog import NAV_STATE_NUMBERS, ULOG_MAGIC

_TYPES = {  # ULog type -> numpy dtype (little-endian)
    "uint64_t": "<u8", "int32_t": "<i4", "uint16_t": "<u2", "uint8_t": "u1", "bool": "u1", "float": "<f4",
    "double": "<f8",
}
_TOPICS = {
    "vehicle_local_position": [
        ("uint64_t", "timestamp"), ("double", "ref_lat"), ("double", "ref_lon"), ("float", "x"), ("float", "y"),
        ("float", "z"), ("float", "vx"), ("float", "vy"), ("float", "vz"), ("float", "heading"),
        ("float", "ref_alt"), ("bool", "xy_valid"), ("bool", "z_valid"), ("bool", "v_xy_valid"),
        ("bool", "v_z_valid"), ("bool", "xy_global"), ("bool", "z_global")],
    "vehicle_status": [
        ("uint64_t", "timestamp"), ("uint8_t", "nav_state"), ("uint8_t", "arming_state"),
        ("uint8_t", "vehicle_type")],
    "home_position": [
        ("uint64_t", "timestamp"), ("double", "lat"), ("double", "lon"), ("float", "alt"), ("float", "x"),
        ("float", "y"), ("float", "z"), ("bool", "valid_alt"), ("bool", "valid_hpos"), ("bool", "valid_lpos")],
    "mission": [("uint64_t", "timestamp"), ("uint16_t", "count"), ("uint16_t", "current_seq")],
    "navigator_mission_item": [
        ("uint64_t", "timestamp"), ("double", "latitude"), ("double", "longitude"), ("float", "time_inside"),
        ("float", "acceptance_radius"), ("float", "altitude"), ("uint16_t", "sequence_current"),
        ("uint16_t", "nav_cmd"), ("uint8_t", "frame"), ("bool", "altitude_is_relative"),
        ("bool", "autocontinue")],
}
_FRAME_GLOBAL_RELATIVE_ALT = 3
_ARMED, _ROTARY_WING = 2, 1


def _message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def _key_value(ulog_type: str, name: str, value: bytes) -> bytes:
    key = f"{ulog_type} {name}".encode()
    return struct.pack("<B", len(key)) + key + value


def _data_messages(msg_id: int, fields, columns: Mapping[str, np.ndarray], n: int) -> bytes:
    """``n`` packed ``D`` messages of one topic, built as one numpy record array."""
    payload = [(name, _TYPES[t]) for t, name in fields]
    size = 2 + sum(np.dtype(d).itemsize for _, d in payload)
    rec = np.zeros(n, dtype=[("_size", "<u2"), ("_type", "u1"), ("_msg_id", "<u2")] + payload)
    rec["_size"], rec["_type"], rec["_msg_id"] = size, ord("D"), msg_id
    for name, _ in payload:
        if name in columns:
            rec[name] = columns[name]
    return rec.tobytes()


def write_ulog(path, timestamp_us, x, y, z, vx, vy, vz, heading, params: Mapping[str, float] | None = None,
               mission: Mission | None = None, *, home: tuple[float, float, float] | None = None,
               nav_state: str = "AUTO_MISSION", sys_name: str = "surrealist-gym") -> None:
    """Write local-position samples as a ULog with a ``vehicle_local_position`` topic.

    Args:
        path: output file (str or PathLike) or a writable binary file.
        timestamp_us: (N,) sample times [us], non-decreasing.
        x, y, z: (N,) position NED [m] (x north, y east, z DOWN), as PX4 logs it.
        vx, vy, vz: (N,) velocity NED [m/s].
        heading: (N,) yaw [rad] from north toward east.
        params: PX4 parameters (int -> int32_t, anything else -> float).
        mission: written as ``mission`` + ``navigator_mission_item`` so that ``read_flight`` returns it.
        home: (lat [deg], lon [deg], alt [m AMSL]) of the local origin; default: the mission's home, if any.
        nav_state: PX4 flight mode of the whole run (a ``vehicle_status.nav_state`` name).

    Example::

        write_ulog("run.ulg", t_us, x, y, z, vx, vy, vz, yaw, params={"MPC_XY_CRUISE": 5.0})
        read_flight("run.ulg").trajectory          # the same pipeline as for a real log
    """
    cols = {"timestamp": np.asarray(timestamp_us, dtype=np.int64)}
    n = cols["timestamp"].shape[0]
    for name, values in zip(("x", "y", "z", "vx", "vy", "vz", "heading"), (x, y, z, vx, vy, vz, heading)):
        cols[name] = np.asarray(values, dtype=np.float64)
        if cols[name].shape != (n,):
            raise ValueError(f"write_ulog: {name} must have shape ({n},), got {cols[name].shape}")
    if n == 0:
        raise ValueError("write_ulog: no samples")
    if np.any(np.diff(cols["timestamp"]) < 0) or cols["timestamp"][0] < 0:
        raise ValueError("write_ulog: timestamp_us must be non-negative and non-decreasing")
    if nav_state not in NAV_STATE_NUMBERS:
        raise ValueError(f"write_ulog: unknown nav_state {nav_state!r} (expected one of {sorted(NAV_STATE_NUMBERS)})")
    if home is None and mission is not None:
        home = mission.home
    t0 = int(cols["timestamp"][0])
    ok = np.isfinite(cols["x"]) & np.isfinite(cols["y"]) & np.isfinite(cols["z"])
    cols.update(xy_valid=ok, z_valid=ok, v_xy_valid=ok, v_z_valid=ok, xy_global=home is not None,
                z_global=home is not None)
    if home is not None:
        cols.update(ref_lat=home[0], ref_lon=home[1], ref_alt=home[2])

    topics = [("vehicle_local_position", cols, n),
              ("vehicle_status", {"timestamp": t0, "nav_state": NAV_STATE_NUMBERS[nav_state],
                                  "arming_state": _ARMED, "vehicle_type": _ROTARY_WING}, 1)]
    if home is not None:
        topics.append(("home_position", {"timestamp": t0, "lat": home[0], "lon": home[1], "alt": home[2],
                                         "valid_alt": 1, "valid_hpos": 1, "valid_lpos": 1}, 1))
    if mission is not None and mission.items:
        topics.append(("mission", {"timestamp": t0, "count": len(mission.items), "current_seq": 0}, 1))
        topics.append(("navigator_mission_item", _mission_columns(mission, t0), len(mission.items)))

    out = bytearray(ULOG_MAGIC + b"\x01" + struct.pack("<Q", t0))
    out += _message(b"B", bytes(16) + struct.pack("<3Q", 0, 0, 0))
    for name, _, _ in topics:
        fmt = name + ":" + "".join(f"{t} {f};" for t, f in _TOPICS[name])
        out += _message(b"F", fmt.encode())
    value = sys_name.encode()
    out += _message(b"I", _key_value(f"char[{len(value)}]", "sys_name", value))
    for pname, pvalue in (params or {}).items():
        if isinstance(pvalue, (int, np.integer)) and not isinstance(pvalue, bool):
            out += _message(b"P", _key_value("int32_t", pname, struct.pack("<i", int(pvalue))))
        else:
            out += _message(b"P", _key_value("float", pname, struct.pack("<f", float(pvalue))))
    for msg_id, (name, _, _) in enumerate(topics):
        out += _message(b"A", struct.pack("<BH", 0, msg_id) + name.encode())
    # single-sample topics are stamped t0, so writing them before the position stream keeps time order
    for msg_id, (name, columns, count) in reversed(list(enumerate(topics))):
        out += _data_messages(msg_id, _TOPICS[name], columns, count)

    if hasattr(path, "write"):
        path.write(bytes(out))
    else:
        with open(os.fspath(path), "wb") as f:
            f.write(out)


def write_run_ulog(path, run, mission: Mission | None = None) -> None:
    """Write a simulated run (a :class:`~surrealist_gym.sim.runner.RunResult`: its recorded local position and its
    parameters) as a ULog that pyulog and :func:`~surrealist_gym.logs.read_flight` read."""
    lp = run.local_position
    write_ulog(path, lp.timestamp_us, lp.x, lp.y, lp.z, lp.vx, lp.vy, lp.vz, lp.heading,
               params=dict(run.params), mission=mission)


def _mission_columns(mission: Mission, t0: int) -> dict[str, np.ndarray]:
    lat0, lon0, _ = mission.home
    lat, lon, alt = [], [], []
    for it in mission.items:
        la, lo = local_to_geo(it.x, it.y, lat0, lon0) if it.has_position else (lat0, lon0)
        lat.append(la)
        lon.append(lo)
        alt.append(it.z if it.has_position else 0.0)
    return {
        "timestamp": np.full(len(lat), t0), "latitude": lat, "longitude": lon, "altitude": alt,
        "time_inside": [it.hold_s for it in mission.items],
        "acceptance_radius": [it.acceptance_radius for it in mission.items],
        "sequence_current": np.arange(len(lat)), "nav_cmd": [int(Command(it.command)) for it in mission.items],
        "frame": _FRAME_GLOBAL_RELATIVE_ALT, "altitude_is_relative": 1, "autocontinue": 1,
    }

