"""MAVLink telemetry logs (``.tlog``) and ArduPilot DataFlash logs (``.bin``) -> :class:`FlightLog`, via pymavlink.

Positions, in order of preference:
- tlog: ``LOCAL_POSITION_NED`` (x, y, z NED; heading from ``ATTITUDE.yaw``), else ``GLOBAL_POSITION_INT``
  projected to the local frame around its first fix (z = -relative_alt; heading from ``hdg``).
- DataFlash: the EKF's local position ``XKF1`` (EKF3, core 0) or ``NKF1`` (EKF2): PN, PE, PD and Yaw; else
  ``POS`` or ``GPS`` (fix >= 3D) projected around their first sample.
Sample times are the vehicle's (``time_boot_ms``, ``TimeUS``), so the trajectory pipeline applies unchanged.
In a tlog, flight-mode and log times are the recorder's clock; vehicle times are aligned to it by their median
offset.
"""
from __future__ import annotations

import contextlib
import io
import math
import os

import numpy as np

from ..errors import LogFormatError
from ..mission import Command, Mission, MissionItem, geo_to_local
from .flight import MAV_TYPE_KIND, FlightLog, LocalPositions, mode_spans

_MAV_AUTOPILOT_INVALID, _MAV_AUTOPILOT_ARDUPILOT, _MAV_AUTOPILOT_PX4 = 8, 3, 12
_MAV_TYPE_GCS = 6
_ABSOLUTE_ALT_FRAMES = {0, 5}  # MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_INT: altitude AMSL
_ARDUPILOT_FIRMWARE = {1: "ArduPlane", 2: "ArduCopter", 3: "ArduCopter", 4: "ArduCopter", 10: "Rover", 11: "Rover",
                       12: "ArduSub", 13: "ArduCopter", 14: "ArduCopter", 15: "ArduCopter", 7: "Blimp"}
_FIRMWARE_MAV_TYPE = {"ArduPlane": 1, "ArduCopter": 2, "APM:Copter": 2, "Rover": 10, "ArduRover": 10, "ArduSub": 12,
                      "Blimp": 7, "APM:Plane": 1}
DATAFLASH_MAGIC = b"\xa3\x95"
MAVLINK_STX = (0xFE, 0xFD)  # MAVLink 1 / MAVLink 2 start bytes
_TLOG, _DATAFLASH = "MAVLink telemetry log", "DataFlash log"
_TLOG_TYPES = ["HEARTBEAT", "LOCAL_POSITION_NED", "GLOBAL_POSITION_INT", "ATTITUDE", "PARAM_VALUE", "HOME_POSITION",
               "GPS_GLOBAL_ORIGIN"]
_DF_TYPES = ["XKF1", "NKF1", "POS", "GPS", "PARM", "MODE", "MSG", "ORGN", "CMD"]


def _messages(path: str, types: list[str], what: str):
    """All messages of ``types`` in the log, in file order; pymavlink failures become LogFormatError."""
    from pymavlink import mavutil

    out = []
    try:
        with open(path, "rb") as f:
            head = f.read(16)
        if what == _DATAFLASH and not head.startswith(DATAFLASH_MAGIC):
            raise LogFormatError(f"{path}: not an ArduPilot DataFlash log (the file does not start with 0xA3 0x95)")
        if what == _TLOG and not (len(head) > 8 and head[8] in MAVLINK_STX):
            raise LogFormatError(f"{path}: not a MAVLink telemetry log (no MAVLink frame after the 8-byte timestamp)")
        # pymavlink prints on bad data (DataFlash to stderr): keep library output quiet
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            conn = mavutil.mavlink_connection(path, robust_parsing=True, notimestamps=False)
            try:
                while True:
                    msg = conn.recv_match(type=types)
                    if msg is None:
                        break
                    out.append(msg)
            finally:
                conn.close()
    except LogFormatError:
        raise
    except OSError as err:
        raise LogFormatError(f"{path}: cannot read {what} ({err.strerror or err})") from err
    except Exception as err:  # noqa: BLE001 - pymavlink raises assorted errors on corrupt input
        raise LogFormatError(f"{path}: corrupt {what} ({type(err).__name__}: {err})") from err
    return out


def _by_type(msgs) -> dict[str, list]:
    groups: dict[str, list] = {}
    for m in msgs:
        groups.setdefault(m.get_type(), []).append(m)
    return groups


def _first_params(pairs) -> dict[str, float]:
    params: dict[str, float] = {}
    for name, value in pairs:
        name = name.decode(errors="replace") if isinstance(name, bytes) else str(name)
        name = name.rstrip("\x00")
        if name and name not in params and math.isfinite(value):
            params[name] = int(value) if float(value).is_integer() else float(value)
    return params


def _project(t_us, lat, lon, up, heading=None) -> LocalPositions:
    """Geographic samples -> local NED around the first one (PX4's azimuthal equidistant projection)."""
    lat0, lon0 = float(lat[0]), float(lon[0])
    ne = np.array([geo_to_local(float(a), float(b), lat0, lon0) for a, b in zip(lat, lon)])
    return LocalPositions(t_us, ne[:, 0], ne[:, 1], -np.asarray(up, dtype=np.float64), heading)


# --- MAVLink telemetry log -----------------------------------------------------------------------------------------
def read_tlog(path) -> FlightLog:
    """Read a MAVLink telemetry log (``.tlog``: 8-byte timestamp + MAVLink 1/2 frame, repeated).

    Raises:
        LogFormatError: unreadable, or no valid position (LOCAL_POSITION_NED or GLOBAL_POSITION_INT with a fix).
    """
    from pymavlink import mavutil

    name = os.fspath(path)
    g = _by_type(_messages(name, _TLOG_TYPES, _TLOG))
    beats = [m for m in g.get("HEARTBEAT", ()) if m.autopilot != _MAV_AUTOPILOT_INVALID and m.type != _MAV_TYPE_GCS]
    sysid = beats[0].get_srcSystem() if beats else None

    def mine(kind):
        return [m for m in g.get(kind, ()) if sysid is None or m.get_srcSystem() == sysid]

    stamps = [m._timestamp for msgs in g.values() for m in msgs]
    start_us = int(min(stamps) * 1e6) if stamps else 0
    end_us = int(max(stamps) * 1e6) if stamps else 0
    positions = _tlog_positions(name, mine("LOCAL_POSITION_NED"), mine("GLOBAL_POSITION_INT"), mine("ATTITUDE"))
    modes = mode_spans([int(m._timestamp * 1e6) for m in beats], [mavutil.mode_string_v10(m) for m in beats],
                       start_us, end_us)
    params = _first_params((m.param_id, m.param_value) for m in mine("PARAM_VALUE"))
    home = None
    for kind, la, lo, al in (("HOME_POSITION", "latitude", "longitude", "altitude"),
                             ("GPS_GLOBAL_ORIGIN", "latitude", "longitude", "altitude")):
        if home is None and mine(kind):
            m = mine(kind)[0]
            home = (getattr(m, la) / 1e7, getattr(m, lo) / 1e7, getattr(m, al) / 1e3)
    vehicle = "unknown (no vehicle HEARTBEAT)"
    if beats:
        kind = MAV_TYPE_KIND.get(beats[0].type, f"MAV_TYPE {beats[0].type}")
        if beats[0].autopilot == _MAV_AUTOPILOT_ARDUPILOT:
            vehicle = f"{_ARDUPILOT_FIRMWARE.get(beats[0].type, 'ArduPilot')} ({kind})"
        elif beats[0].autopilot == _MAV_AUTOPILOT_PX4:
            vehicle = f"{kind} (PX4)"
        else:
            vehicle = f"{kind} (MAV_AUTOPILOT {beats[0].autopilot})"
    return FlightLog(path=name, format="tlog", positions=positions, params=params, modes=modes, home=home,
                     vehicle_type=vehicle, start_us=start_us, end_us=end_us)


def _aligned_times(msgs) -> np.ndarray:
    """Vehicle times [us] of messages with ``time_boot_ms``, shifted onto the recorder's clock."""
    boot = np.array([m.time_boot_ms for m in msgs], dtype=np.int64) * 1000
    recv = np.array([int(m._timestamp * 1e6) for m in msgs], dtype=np.int64)
    return boot + int(np.median(recv - boot))


def _tlog_positions(name, local, glob, attitude) -> LocalPositions:
    local = _unique_times([m for m in local if math.isfinite(m.x + m.y + m.z)])
    if local:
        t = _aligned_times(local)
        heading = None
        if attitude:
            at = np.array([m.time_boot_ms for m in attitude], dtype=np.float64)
            yaw = np.unwrap(np.array([m.yaw for m in attitude], dtype=np.float64))
            order = np.argsort(at, kind="stable")
            boot = np.array([m.time_boot_ms for m in local], dtype=np.float64)
            heading = (np.interp(boot, at[order], yaw[order]) + math.pi) % (2 * math.pi) - math.pi
        return LocalPositions(t, [m.x for m in local], [m.y for m in local], [m.z for m in local], heading)
    fixes = _unique_times([m for m in glob if m.lat != 0 or m.lon != 0])
    if not fixes:
        why = "GLOBAL_POSITION_INT has no fix (lat = lon = 0)" if glob else "no GLOBAL_POSITION_INT"
        raise LogFormatError(f"no valid local position in {name} (no LOCAL_POSITION_NED; {why})")
    hdg = np.array([m.hdg for m in fixes], dtype=np.float64)
    heading = None if np.any(hdg == 65535) else np.radians(hdg / 100.0)
    return _project(_aligned_times(fixes), [m.lat / 1e7 for m in fixes], [m.lon / 1e7 for m in fixes],
                    [m.relative_alt / 1e3 for m in fixes], heading)


def _unique_times(msgs) -> list:
    """Drop repeated ``time_boot_ms`` (the same sample relayed twice)."""
    seen, out = set(), []
    for m in msgs:
        if m.time_boot_ms not in seen:
            seen.add(m.time_boot_ms)
            out.append(m)
    return out


# --- ArduPilot DataFlash log ---------------------------------------------------------------------------------------
def read_dataflash(path) -> FlightLog:
    """Read an ArduPilot DataFlash log (``.bin``); a log cut mid-message is read up to the cut.

    Raises:
        LogFormatError: unreadable, or none of XKF1, NKF1, POS, GPS (with a 3-D fix) holds a position.
    """
    from pymavlink import mavutil

    name = os.fspath(path)
    g = _by_type(_messages(name, _DF_TYPES, _DATAFLASH))
    stamps = [m.TimeUS for msgs in g.values() for m in msgs if hasattr(m, "TimeUS")]
    start_us, end_us = (int(min(stamps)), int(max(stamps))) if stamps else (0, 0)
    positions = _dataflash_positions(name, g)
    firmware = next((m.Message.split(" (")[0] for m in g.get("MSG", ())
                     if m.Message.split(" ")[0] in _FIRMWARE_MAV_TYPE), None)
    mav_type = _FIRMWARE_MAV_TYPE.get(firmware.split(" ")[0]) if firmware else None
    if firmware:
        vehicle = f"{firmware} ({MAV_TYPE_KIND.get(mav_type, 'vehicle')})"
    else:
        vehicle = "ArduPilot (firmware not named in the log)"
    mapping = (mavutil.mode_mapping_bynumber(mav_type) or {}) if mav_type is not None else {}
    mode_msgs = g.get("MODE", ())
    modes = mode_spans([m.TimeUS for m in mode_msgs],
                       [mapping.get(m.ModeNum if hasattr(m, "ModeNum") else m.Mode, f"MODE_{m.Mode}")
                        for m in mode_msgs], start_us, end_us)
    params = _first_params((m.Name, m.Value) for m in g.get("PARM", ()))
    origins = sorted(g.get("ORGN", ()), key=lambda m: -m.Type)  # Type 1 = home, before Type 0 = EKF origin
    home = (origins[0].Lat, origins[0].Lng, origins[0].Alt) if origins else None
    mission = _dataflash_mission(name, g.get("CMD", ()))
    if home is None and mission is not None:
        home = mission.home
    return FlightLog(path=name, format="dataflash", positions=positions, mission=mission, params=params,
                     modes=modes, home=home, vehicle_type=vehicle, start_us=start_us, end_us=end_us)


def _dataflash_positions(name: str, g) -> LocalPositions:
    why = "no XKF1, NKF1, POS or GPS with a 3-D fix"
    for kind in ("XKF1", "NKF1"):
        msgs = [m for m in g.get(kind, ()) if getattr(m, "C", 0) == 0 and math.isfinite(m.PN + m.PE + m.PD)]
        if msgs and all(m.PN == 0 and m.PE == 0 for m in msgs):  # the EKF never had a horizontal position
            why = f"{kind}.PN and {kind}.PE are always 0 and there is no POS or GPS with a 3-D fix"
        elif msgs:
            return LocalPositions([m.TimeUS for m in msgs], [m.PN for m in msgs], [m.PE for m in msgs],
                                  [m.PD for m in msgs], np.radians([m.Yaw for m in msgs]))
    pos = [m for m in g.get("POS", ()) if m.Lat != 0 or m.Lng != 0]
    if pos:
        return _project([m.TimeUS for m in pos], [m.Lat for m in pos], [m.Lng for m in pos],
                        [m.Alt - pos[0].Alt for m in pos])
    gps = [m for m in g.get("GPS", ()) if getattr(m, "Status", 0) >= 3]
    if gps:
        return _project([m.TimeUS for m in gps], [m.Lat for m in gps], [m.Lng for m in gps],
                        [m.Alt - gps[0].Alt for m in gps])
    raise LogFormatError(f"no valid local position in {name} ({why})")


def _dataflash_mission(name: str, cmds) -> Mission | None:
    """The mission from CMD messages: number 0 is home, the rest are items (altitude relative to home)."""
    by_num = {}
    for m in cmds:
        by_num.setdefault(int(m.CNum), m)
    if 0 not in by_num or len(by_num) < 2:
        return None
    home = (float(by_num[0].Lat), float(by_num[0].Lng), float(by_num[0].Alt))
    items, skipped = [], []
    for num in sorted(by_num)[1:]:
        m = by_num[num]
        try:
            command = Command(int(m.CId))
        except ValueError:
            skipped.append(f"{name}: CMD {num}: MAV_CMD {int(m.CId)} is not supported (skipped)")
            continue
        if command == Command.CHANGE_SPEED:
            items.append(MissionItem(command, speed=float(m.Prm2)))
        elif command == Command.RETURN_TO_LAUNCH:
            items.append(MissionItem(command))
        else:
            lat, lon = (m.Lat, m.Lng) if (m.Lat != 0 or m.Lng != 0) else home[:2]
            north, east = geo_to_local(float(lat), float(lon), home[0], home[1])
            up = float(m.Alt) - home[2] if getattr(m, "Frame", 3) in _ABSOLUTE_ALT_FRAMES else float(m.Alt)
            hold = float(m.Prm1) if command == Command.WAYPOINT else 0.0
            items.append(MissionItem(command, north, east, up, hold_s=hold))
    return Mission(tuple(items), home, None, tuple(skipped), name)
