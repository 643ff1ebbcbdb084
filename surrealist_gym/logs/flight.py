"""The immutable :class:`FlightLog` value that every log reader returns.

Frames and times: raw samples are local NED as logged (x north, y east, z DOWN, metres; timestamps in
microseconds of the vehicle's clock). ``FlightLog.trajectory`` is the paper's pipeline over the whole log
(:meth:`~surrealist_gym.trajectory.Trajectory.from_local_position`: z up, origin at the first sample, 0.5 s
windows). Flight-mode spans are in seconds since the start of the log (``start_us``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from ..errors import FrozenDict, LogFormatError
from ..mission import Mission
from ..trajectory import Trajectory, frozen_array as _frozen


@dataclass(frozen=True, slots=True, eq=False)
class LocalPositions:
    """Raw local-position samples as logged, sorted by time.

    Attributes:
        timestamp_us: (N,) int64 sample times [us], vehicle clock.
        x: (N,) north [m].
        y: (N,) east [m].
        z: (N,) down [m] (NED, as PX4 and ArduPilot log it).
        heading: (N,) yaw [rad] from north toward east, or None when the log has none.
    """

    timestamp_us: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    heading: np.ndarray | None = None

    def __post_init__(self):
        ts = np.asarray(self.timestamp_us, dtype=np.int64)
        order = np.argsort(ts, kind="stable")
        object.__setattr__(self, "timestamp_us", _frozen(ts[order], np.int64))
        for name in ("x", "y", "z"):
            col = np.asarray(getattr(self, name), dtype=np.float64)
            if col.shape != ts.shape:
                raise ValueError(f"LocalPositions.{name} must have shape {ts.shape}, got {col.shape}")
            object.__setattr__(self, name, _frozen(col[order], np.float64))
        if self.heading is not None:
            heading = np.asarray(self.heading, dtype=np.float64)
            if heading.shape != ts.shape:
                raise ValueError(f"LocalPositions.heading must have shape {ts.shape}, got {heading.shape}")
            object.__setattr__(self, "heading", _frozen(heading[order], np.float64))

    def __len__(self) -> int:
        return int(self.timestamp_us.shape[0])

    def between(self, t0_us: int, t1_us: int) -> "LocalPositions":
        """The samples with ``t0_us <= timestamp_us <= t1_us``."""
        m = (self.timestamp_us >= t0_us) & (self.timestamp_us <= t1_us)
        heading = None if self.heading is None else self.heading[m]
        return LocalPositions(self.timestamp_us[m], self.x[m], self.y[m], self.z[m], heading)

    def trajectory(self) -> Trajectory:
        """The paper's pipeline over these samples (first timestamp and position subtracted, 0.5 s windows)."""
        return Trajectory.from_local_position(self.timestamp_us, self.x, self.y, self.z, self.heading)


@dataclass(frozen=True, slots=True)
class ModeSpan:
    """One flight-mode span: ``start``/``end`` in seconds since the start of the log, and the mode's name.

    PX4 modes use the ``vehicle_status.nav_state`` names (AUTO_MISSION, AUTO_TAKEOFF, POSCTL, ...); ArduPilot
    modes use pymavlink's names (AUTO, GUIDED, MANUAL, ...).
    """

    start: float
    end: float
    mode: str

    @property
    def duration(self) -> float:
        """Length of the span [s]."""
        return self.end - self.start


@dataclass(frozen=True, slots=True, eq=False)
class FlightLog:
    """Everything surrealist-gym uses from one flight log.

    Attributes:
        path: the log file.
        format: ``"ulog"``, ``"tlog"`` or ``"dataflash"``.
        positions: the raw (valid) local-position samples, NED.
        mission: the mission flown, from the log's mission items, or None when the log has none.
        params: parameter name -> value (the values at the start of the log).
        modes: flight-mode timeline, in time order.
        home: (lat [deg], lon [deg], alt [m AMSL]) of the home / local-frame origin, or None.
        vehicle_type: e.g. ``"multirotor (PX4 airframe 4016)"`` or ``"ArduSub V4.1.0 (submarine)"``.
        start_us: first timestamp of the log [us]; mode spans count from here.
        end_us: last timestamp of the log [us].
        damage: how the file is damaged, e.g. "the file ends inside a message at byte 1244978: truncated, positions
            readable for 21.7 s"; empty for a whole log (checked for ULogs).
        trajectory: the paper's pipeline over all of ``positions`` (computed, z up).

    Example::

        flight = surrealist_gym.read_flight("case0.ulg")
        len(flight.trajectory)                     # 86 points of 0.5 s
        flight.mission_trajectory()                # just the AUTO_MISSION segment
    """

    path: str
    format: str
    positions: LocalPositions
    mission: Mission | None = None
    params: Mapping[str, float] = field(default_factory=dict)
    modes: tuple[ModeSpan, ...] = ()
    home: tuple[float, float, float] | None = None
    vehicle_type: str = "unknown"
    start_us: int = 0
    end_us: int = 0
    damage: str = ""
    trajectory: Trajectory = field(init=False)

    def __post_init__(self):
        if len(self.positions) == 0:
            raise LogFormatError(f"no valid local position in {self.path}")
        object.__setattr__(self, "params", FrozenDict(dict(self.params)))
        object.__setattr__(self, "modes", tuple(self.modes))
        if self.home is not None:
            object.__setattr__(self, "home", tuple(float(v) for v in self.home))
        object.__setattr__(self, "trajectory", self.positions.trajectory())

    @property
    def duration(self) -> float:
        """Length of the log [s] (first to last timestamp of any message)."""
        return (self.end_us - self.start_us) / 1e6

    def mode_durations(self) -> dict[str, float]:
        """Total time [s] spent in each flight mode, in order of first appearance."""
        out: dict[str, float] = {}
        for span in self.modes:
            out[span.mode] = out.get(span.mode, 0.0) + span.duration
        return out

    def segment_span(self, mode: str = "AUTO_MISSION") -> ModeSpan:
        """The longest span of ``mode``; LogFormatError when the log never enters it."""
        spans = [s for s in self.modes if s.mode == mode]
        if not spans:
            seen = ", ".join(dict.fromkeys(s.mode for s in self.modes)) or "none"
            raise LogFormatError(f"{self.path}: flight mode {mode} never entered (modes in the log: {seen})")
        return max(spans, key=lambda s: s.duration)

    def segment(self, mode: str = "AUTO_MISSION") -> Trajectory:
        """The pipeline applied to the local positions of the longest span of ``mode`` only.

        The first timestamp and position of the segment are subtracted, so the segment starts at t = 0 at the
        origin, as a simulated run of the same mission does.
        """
        span = self.segment_span(mode)
        t0 = self.start_us + int(math.floor(span.start * 1e6))
        t1 = self.start_us + int(math.ceil(span.end * 1e6))
        part = self.positions.between(t0, t1)
        if len(part) == 0:
            raise LogFormatError(f"{self.path}: no valid local position during {mode} "
                                 f"({span.start:.1f} s to {span.end:.1f} s)")
        return part.trajectory()

    @property
    def mission_mode(self) -> str | None:
        """The autonomous mission mode the log enters: AUTO_MISSION (PX4) or AUTO (ArduPilot), else None."""
        names = {s.mode for s in self.modes}
        return next((m for m in ("AUTO_MISSION", "AUTO") if m in names), None)

    def mission_trajectory(self) -> Trajectory:
        """:meth:`segment` of the mission mode (:attr:`mission_mode`); LogFormatError when there is none."""
        return self.segment(self.mission_mode or "AUTO_MISSION")


def mode_spans(times_us, names, start_us: int, end_us: int) -> tuple[ModeSpan, ...]:
    """Collapse a time series of mode names into spans (consecutive equal names merge; last span ends at end_us)."""
    spans: list[ModeSpan] = []
    cur_name, cur_t = None, None
    for t, name in zip(times_us, names):
        t = max(int(t), start_us)
        if name != cur_name:
            if cur_name is not None:
                spans.append(ModeSpan((cur_t - start_us) / 1e6, (t - start_us) / 1e6, cur_name))
            cur_name, cur_t = name, t
    if cur_name is not None:
        spans.append(ModeSpan((cur_t - start_us) / 1e6, (max(end_us, cur_t) - start_us) / 1e6, cur_name))
    return tuple(spans)


MAV_TYPE_KIND = {
    1: "fixed-wing", 2: "multirotor", 3: "multirotor", 4: "helicopter", 10: "ground rover", 11: "surface boat",
    12: "submarine", 13: "multirotor", 14: "multirotor", 15: "multirotor", 19: "VTOL", 20: "VTOL", 21: "VTOL",
    22: "VTOL", 23: "VTOL", 24: "VTOL", 25: "VTOL", 29: "multirotor",
}
