"""PX4 ULog (``.ulg``) -> :class:`FlightLog`, decoded by pyulog.

Topics used: ``vehicle_local_position`` (samples with ``xy_valid`` and ``z_valid`` set; ``heading``, or ``yaw``
in 2016-era logs), ``vehicle_status.nav_state`` (flight modes), ``home_position`` (home; else the local
position's reference ``ref_lat/ref_lon/ref_alt``), ``navigator_mission_item`` and ``mission`` (the mission
items, as the navigator executed them) and the initial parameters (``SYS_AUTOSTART``, ``MAV_TYPE``, ...).
"""
from __future__ import annotations

import contextlib
import io
import logging
import math
import os
import warnings

import numpy as np

from ..errors import LogFormatError
from ..mission import Command, Mission, MissionItem, geo_to_local
from .flight import MAV_TYPE_KIND, FlightLog, LocalPositions, mode_spans

log = logging.getLogger(__name__)

ULOG_MAGIC = b"ULog\x01\x12\x35"
TOPICS = ["vehicle_local_position", "vehicle_status", "home_position", "navigator_mission_item", "mission"]

# vehicle_status.nav_state -> name (PX4 vehicle_status.msg; 6-9, 11 and 16 were renamed or freed over versions).
NAV_STATES = {
    0: "MANUAL", 1: "ALTCTL", 2: "POSCTL", 3: "AUTO_MISSION", 4: "AUTO_LOITER", 5: "AUTO_RTL",
    6: "POSITION_SLOW", 7: "AUTO_RTGS", 8: "AUTO_LANDENGFAIL", 9: "AUTO_LANDGPSFAIL", 10: "ACRO",
    11: "UNUSED", 12: "DESCEND", 13: "TERMINATION", 14: "OFFBOARD", 15: "STAB", 16: "RATTITUDE",
    17: "AUTO_TAKEOFF", 18: "AUTO_LAND", 19: "AUTO_FOLLOW_TARGET", 20: "AUTO_PRECLAND", 21: "ORBIT",
    22: "AUTO_VTOL_TAKEOFF",
}
NAV_STATE_NUMBERS = {name: number for number, name in NAV_STATES.items()}
_STATUS_VEHICLE_TYPE = {1: "multirotor", 2: "fixed-wing", 3: "ground rover", 4: "airship"}


def parse_ulog(source, topics=None):
    """Decode a ULog with pyulog; any failure becomes a one-line LogFormatError.

    Args:
        source: a path (str or PathLike) or a binary file positioned at the start of the log.
        topics: the topic names to decode (None: all).
    """
    from pyulog import ULog

    name = _name(source)
    stall = None
    try:
        if hasattr(source, "read"):
            start = source.tell()
            head = source.read(len(ULOG_MAGIC))
            source.seek(start)
        else:
            with open(source, "rb") as f:
                head = f.read(len(ULOG_MAGIC))
                stall = _definitions_stall(head + f.read()) if head == ULOG_MAGIC else None
    except OSError as err:
        raise LogFormatError(f"{name}: cannot read log file ({err.strerror or err})") from err
    if head != ULOG_MAGIC:
        raise LogFormatError(f"{name}: not a ULog file (the file does not start with the ULog magic bytes)")
    if stall is not None:
        raise LogFormatError(f"{name}: corrupt ULog (a damaged message header at byte {stall}, in the definitions "
                             f"before the data)")
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter):  # pyulog prints its warnings
            ulog = ULog(source if hasattr(source, "read") else os.fspath(source), topics)
    except Exception as err:  # noqa: BLE001 - pyulog raises TypeError/struct.error/IndexError/... on corrupt input
        raise LogFormatError(f"{name}: corrupt or truncated ULog ({type(err).__name__}: {err})") from err
    if chatter.getvalue().strip():
        log.debug("pyulog on %s: %s", name, chatter.getvalue().strip())
    return ulog


def read_ulog(source) -> FlightLog:
    """Read a PX4 ULog into a :class:`FlightLog`.

    Raises:
        LogFormatError: not a ULog, corrupt, or no valid local position (one line naming file and topic/field).

    Example::

        flight = read_ulog("case0.ulg")
        flight.modes[0].mode                       # 'AUTO_MISSION'
    """
    name = _name(source)
    ulog = parse_ulog(source, TOPICS)
    data = {}
    for d in ulog.data_list:
        if d.multi_id == 0 or d.name not in data:
            data[d.name] = d.data
    lp, status = data.get("vehicle_local_position"), data.get("vehicle_status")
    # each topic's samples on the log's timeline (flipped bits in a timestamp throw a sample seconds to days away)
    lp_on = None if lp is None or "timestamp" not in lp else on_timeline(lp["timestamp"])
    status_on = None if status is None or "timestamp" not in status else on_timeline(status["timestamp"])
    start_us, end_us, off = _span(ulog, [(lp, lp_on), (status, status_on)])
    positions = _positions(name, lp, start_us, lp_on)
    readable = f"positions readable for {(int(positions.timestamp_us[-1]) - start_us) / 1e6:.1f} s"
    damage = ""
    if ulog.file_corruption or off:
        damage = "; ".join(part for part in (
            "corrupt data in the file was skipped (pyulog resynchronised)" if ulog.file_corruption else "",
            f"damaged timestamps off the log's timeline were set aside ({off})" if off else "") if part)
        damage += f"; {readable}"
    elif not hasattr(source, "read"):
        cut = _truncated_at(os.fspath(source))
        if cut is not None:
            damage = f"the file ends inside a message at byte {cut}: truncated, {readable}"
    if damage:
        warnings.warn(f"{name}: {damage}; the flight it holds may be incomplete", stacklevel=2)
    params = dict(ulog.initial_parameters)
    modes = ()
    if status is not None and "nav_state" in status and np.any(status_on):
        names = [NAV_STATES.get(int(n), f"NAV_STATE_{int(n)}") for n in status["nav_state"][status_on]]
        modes = mode_spans(status["timestamp"][status_on].astype(np.int64), names, start_us, end_us)
    home = _home(data.get("home_position"), data.get("vehicle_local_position"))
    mission = _mission(name, data.get("navigator_mission_item"), data.get("mission"), home)
    return FlightLog(path=name, format="ulog", positions=positions, mission=mission, params=params, modes=modes,
                     home=home, vehicle_type=_vehicle_type(params, status), start_us=start_us, end_us=end_us,
                     damage=damage)


def _name(source) -> str:
    if hasattr(source, "read"):
        return str(getattr(source, "name", "<ULog stream>"))
    return os.fspath(source)


_DATA_SECTION = (ord("A"), ord("L"), ord("C"))  # the message types that end pyulog's definitions section
_DEFINITIONS = tuple(map(ord, "IMFPQB"))  # the ones it reads there (a damaged one it skips whole)


def _definitions_stall(data: bytes) -> int | None:
    """Where pyulog would never leave the definitions section of this ULog (it steps back over a damaged header by
    its stated size, which near the end of the file is further than it read), else None. Follows its reading of
    the section: 3-byte headers (uint16 size, uint8 type), a damaged header of an unknown type (type 0, size 0 or
    over 10,000) skipped by one byte, the section ending at the first data message."""
    pos, n = 16, len(data)
    while pos < n:
        if pos + 3 > n:
            return None  # a short last header: pyulog reads nothing more
        size, kind = data[pos] | data[pos + 1] << 8, data[pos + 2]
        if kind in _DATA_SECTION:
            return None
        end = min(pos + 3 + size, n)
        if kind not in _DEFINITIONS and (kind == 0 or size == 0 or size > 10000):
            if end - 2 - size <= pos:
                return pos
            end -= 2 + size
        pos = end
    return None


def _truncated_at(path: str) -> int | None:
    """The offset of the last, incomplete message when the file ends inside it (a truncated log), else None.
    ULog: a 16-byte header, then messages of (uint16 size, uint8 type, size bytes)."""
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    pos, n = 16, len(data)
    while pos + 3 <= n:
        size = data[pos] | data[pos + 1] << 8
        if pos + 3 + size > n:
            return pos
        pos += 3 + size
    return pos if pos != n else None


def _positions(name: str, lp, start_us: int = 0, on=None) -> LocalPositions:
    """The valid local position samples; ``on``: which of them lie on the log's timeline (:func:`on_timeline`)."""
    if lp is None:
        raise LogFormatError(f"no valid local position in {name} (no vehicle_local_position topic)")
    missing = [k for k in ("timestamp", "x", "y", "z") if k not in lp]
    if missing:
        raise LogFormatError(f"no valid local position in {name} (vehicle_local_position lacks {', '.join(missing)})")
    ok = np.isfinite(lp["x"]) & np.isfinite(lp["y"]) & np.isfinite(lp["z"])
    ok &= on_timeline(lp["timestamp"]) if on is None else on
    ok &= lp["timestamp"].astype(np.int64) >= start_us
    if not np.any(ok):
        raise LogFormatError(f"no valid local position in {name} (vehicle_local_position x/y/z never finite)")
    for flag in ("xy_valid", "z_valid"):
        if flag in lp and not np.any(ok & (lp[flag] != 0)):
            raise LogFormatError(f"no valid local position in {name} (vehicle_local_position.{flag} never set)")
        if flag in lp:
            ok &= lp[flag] != 0
    if not np.any(ok):
        raise LogFormatError(f"no valid local position in {name} (xy_valid and z_valid never set together)")
    heading = lp.get("heading", lp.get("yaw"))
    return LocalPositions(lp["timestamp"][ok].astype(np.int64), lp["x"][ok], lp["y"][ok], lp["z"][ok],
                          None if heading is None else heading[ok])


def on_timeline(timestamps) -> np.ndarray:
    """Which samples of a topic lie on the log's timeline: the longest run of timestamps in the order they were
    logged (a sample whose timestamp jumps backwards or ahead of the rest is off it), without the small islands a
    gap far beyond the sampling interval cuts off (a flipped high bit moves a timestamp by 2^k us: a sample seconds
    to days away, alone there). Intact logs (non-decreasing, no such island) keep every sample."""
    ts = np.asarray(timestamps).astype(np.int64)
    n = len(ts)
    keep = np.ones(n, dtype=bool)
    if n < 3:
        return keep
    if np.any(np.diff(ts) < 0):
        keep = _longest_ordered(ts)
    kept = np.flatnonzero(keep)
    if len(kept) < 3:
        return keep
    steps = np.diff(ts[kept])
    gap = max(ISLAND_GAP_US, 100 * float(np.median(steps)))
    cuts = np.flatnonzero(steps > gap) + 1
    if len(cuts):
        smallest = max(3, len(kept) // 100)  # a stretch of fewer samples between such gaps is an island
        for run in np.split(kept, cuts):
            if len(run) < smallest:
                keep[run] = False
    return keep


ISLAND_GAP_US = 10_000_000  # [us] samples cut off from the rest by over 10 s (or 100 sampling intervals)


def _longest_ordered(ts: np.ndarray) -> np.ndarray:
    """A mask of a longest non-decreasing subsequence of ``ts`` (patience sorting, O(n log n))."""
    import bisect

    tails, tail_at, parent = [], [], np.full(len(ts), -1)
    for i, t in enumerate(ts.tolist()):
        k = bisect.bisect_right(tails, t)
        if k == len(tails):
            tails.append(t)
            tail_at.append(i)
        else:
            tails[k], tail_at[k] = t, i
        parent[i] = tail_at[k - 1] if k else -1
    keep = np.zeros(len(ts), dtype=bool)
    i = tail_at[-1]
    while i >= 0:
        keep[i] = True
        i = parent[i]
    return keep


def _span(ulog, topics) -> tuple[int, int, str]:
    """The log's start and end [us] and what lies off its timeline ("" when nothing does): the header's start and
    last timestamp, unless they lie beyond the first and last samples on the timeline by more than the island gap
    (a damaged timestamp), in which case the samples bound the log."""
    start, end = int(ulog.start_timestamp), int(ulog.last_timestamp)
    dropped = sum(int(len(on) - np.count_nonzero(on)) for data, on in topics if on is not None)
    times = [data["timestamp"][on].astype(np.int64) for data, on in topics if on is not None and np.any(on)]
    if not times:
        return start, end, ""
    first, last = min(int(t[0]) for t in times), max(int(t[-1]) for t in times)
    off = [f"{dropped} sample{'s' if dropped > 1 else ''}"] if dropped else []
    if first - start > ISLAND_GAP_US or start - first > ISLAND_GAP_US:
        off.append("the header's start time")
        start = first
    if end - last > ISLAND_GAP_US or end < start:
        off.append("the log's last timestamp")
        end = last
    return start, end, " and ".join(off)


def _home(hp, lp) -> tuple[float, float, float] | None:
    if hp is not None and len(hp.get("timestamp", ())) and {"lat", "lon", "alt"} <= hp.keys():
        ok = np.ones(len(hp["timestamp"]), dtype=bool)
        if "valid_hpos" in hp:
            ok &= hp["valid_hpos"] != 0
        if np.any(ok):
            i = int(np.flatnonzero(ok)[0])
            return float(hp["lat"][i]), float(hp["lon"][i]), float(hp["alt"][i])
    if lp is not None and {"ref_lat", "ref_lon", "ref_alt"} <= lp.keys():
        ok = np.ones(len(lp["timestamp"]), dtype=bool)
        if "xy_global" in lp:
            ok &= lp["xy_global"] != 0
        ok &= (lp["ref_lat"] != 0) | (lp["ref_lon"] != 0)
        if np.any(ok):
            i = int(np.flatnonzero(ok)[0])
            return float(lp["ref_lat"][i]), float(lp["ref_lon"][i]), float(lp["ref_alt"][i])
    return None


def _mission(name: str, nmi, mission_topic, home) -> Mission | None:
    """The mission from ``navigator_mission_item``: per sequence number, the item the navigator executed.

    PX4 logs each item when it becomes current, sometimes twice (e.g. a LAND item first flown to as a WAYPOINT);
    the non-waypoint record of a sequence number wins. Items never reached are not in the log.
    """
    if nmi is None or not len(nmi.get("timestamp", ())) or home is None:
        return None
    count = int(mission_topic["count"][-1]) if mission_topic is not None and len(mission_topic["count"]) else None
    by_seq: dict[int, int] = {}
    for i, (seq, cmd) in enumerate(zip(nmi["sequence_current"], nmi["nav_cmd"])):
        seq, cmd = int(seq), int(cmd)
        if cmd == 0 or (count is not None and seq >= count):
            continue
        if seq not in by_seq or int(nmi["nav_cmd"][by_seq[seq]]) == Command.WAYPOINT:
            by_seq[seq] = i
    if not by_seq:
        return None
    lat0, lon0, alt0 = home
    items, skipped = [], []
    for seq in sorted(by_seq):
        i = by_seq[seq]
        cmd = int(nmi["nav_cmd"][i])
        try:
            command = Command(cmd)
        except ValueError:
            skipped.append(f"{name}: navigator_mission_item seq {seq}: MAV_CMD {cmd} is not supported (skipped)")
            continue
        if command in (Command.RETURN_TO_LAUNCH, Command.CHANGE_SPEED):
            items.append(MissionItem(command))
            continue
        north, east = geo_to_local(float(nmi["latitude"][i]), float(nmi["longitude"][i]), lat0, lon0)
        alt = float(nmi["altitude"][i])
        up = alt if int(nmi["altitude_is_relative"][i]) else alt - alt0
        radius = float(nmi["acceptance_radius"][i]) if command == Command.WAYPOINT else 0.0
        hold = float(nmi["time_inside"][i]) if command == Command.WAYPOINT else 0.0
        items.append(MissionItem(command, north, east, up, acceptance_radius=radius if math.isfinite(radius) else 0.0,
                                 hold_s=hold))
    if count is not None and len(by_seq) < count:
        skipped.append(f"{name}: {count - len(by_seq)} of {count} mission items never reached (not in the log)")
    return Mission(tuple(items), (lat0, lon0, alt0), None, tuple(skipped), name)


def _vehicle_type(params, status) -> str:
    kind = MAV_TYPE_KIND.get(int(params["MAV_TYPE"])) if "MAV_TYPE" in params else None
    if kind is None and status is not None:
        if "is_vtol" in status and len(status["is_vtol"]) and status["is_vtol"][-1]:
            kind = "VTOL"
        elif "vehicle_type" in status and len(status["vehicle_type"]):
            kind = _STATUS_VEHICLE_TYPE.get(int(status["vehicle_type"][-1]))
        elif "is_rotary_wing" in status and len(status["is_rotary_wing"]):
            kind = "multirotor" if status["is_rotary_wing"][-1] else "fixed-wing"
    kind = kind or "vehicle"
    airframe = params.get("SYS_AUTOSTART")
    return f"{kind} (PX4 airframe {int(airframe)})" if airframe else f"{kind} (PX4)"
