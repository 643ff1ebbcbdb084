"""``surrealist inspect LOG``: describe a flight log (vehicle, modes, mission, extent, key parameters) and plot it.

Example::

    surrealist inspect case0.ulg                 # text summary, plot written to ./case0.png
    surrealist inspect case0.ulg --out plots     # the plot in plots/case0.png
    surrealist inspect case0.ulg --json --no-plot
"""
from __future__ import annotations

import argparse
import json
import math
import os
from pathlib import Path

from ..errors import SurrealistError

KEY_PARAMS = ("MPC_XY_CRUISE", "MPC_XY_VEL_MAX", "MPC_TKO_SPEED", "MPC_LAND_SPEED", "MPC_ACC_HOR", "MPC_THR_HOVER",
              "NAV_ACC_RAD", "MIS_TAKEOFF_ALT", "COM_OBS_AVOID", "CP_DIST", "SYS_AUTOSTART", "MAV_TYPE",
              "WPNAV_SPEED", "WPNAV_ACCEL", "WPNAV_RADIUS", "WP_SPEED", "WP_RADIUS", "FRAME_CLASS")


class _OutFolder(argparse.Action):
    """``--out DIR``; a plot file's name, as ``--out`` took before, is refused in one line with its folder."""

    def __call__(self, parser, namespace, values, option_string=None):
        if Path(values).suffix.lower() in (".png", ".jpg", ".svg", ".pdf") and not Path(values).is_dir():
            folder = Path(values).parent
            parser.error(f"--out is a folder; inspect writes <log name>.png in it: --out {folder}")
        setattr(namespace, self.dest, values)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist inspect``."""
    parser.add_argument("log", metavar="LOG", nargs="?", default=None,
                        help="flight log: PX4 .ulg, MAVLink .tlog or ArduPilot DataFlash .bin "
                             "(default: the bundled real flight case0.ulg)")
    parser.add_argument("--out", metavar="DIR", action=_OutFolder, default=None,
                        help="folder of the plot, <log name>.png (default: the current folder)")
    parser.add_argument("--no-plot", action="store_true", help="do not write the plot")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")


def summary(flight) -> dict:
    """The facts ``inspect`` reports, as a JSON-ready dictionary."""
    ext = flight.trajectory.extent()
    mission = None
    if flight.mission is not None:
        items = []
        for it in flight.mission.items:
            item = {"command": it.command.name.lower(), "mav_cmd": int(it.command)}
            if it.has_position:
                item.update(x=round(it.x, 3), y=round(it.y, 3), z=round(it.z, 3),
                            distance_m=round(math.hypot(it.x, it.y), 2))
            elif not math.isnan(it.speed):
                item["speed"] = it.speed
            items.append(item)
        mission = {"items": items, "skipped": list(flight.mission.skipped)}
    segment = None
    if flight.mission_mode is not None:
        try:
            seg = flight.mission_trajectory()
            segment = {"mode": flight.mission_mode, "points": len(seg), "duration_s": round(seg.duration, 2)}
        except SurrealistError:  # the mode was entered but no valid position was logged during it
            segment = None
    return {
        "path": flight.path,
        "format": flight.format,
        "vehicle": flight.vehicle_type,
        "duration_s": round(flight.duration, 3),
        "damage": flight.damage or None,
        "home": None if flight.home is None else dict(zip(("lat", "lon", "alt"), flight.home)),
        "modes": [{"mode": s.mode, "start_s": round(s.start, 3), "end_s": round(s.end, 3),
                   "duration_s": round(s.duration, 3)} for s in flight.modes],
        "mode_durations_s": {k: round(v, 3) for k, v in flight.mode_durations().items()},
        "trajectory": {"points": len(flight.trajectory), "samples": len(flight.positions),
                       "extent_m": {k: [round(a, 3), round(b, 3)] for k, (a, b) in ext.items()}},
        "mission_segment": segment,
        "mission": mission,
        "params": {k: flight.params[k] for k in KEY_PARAMS if k in flight.params},
        "param_count": len(flight.params),
    }


def _text(info: dict) -> str:
    lines = [f"log         {info['path']} ({info['format']})",
             f"vehicle     {info['vehicle']}",
             f"duration    {info['duration_s']:.1f} s"]
    if info.get("damage"):
        lines.append(f"damaged     {info['damage']}")
    if info["home"]:
        h = info["home"]
        lines.append(f"home        lat {h['lat']:.7f}, lon {h['lon']:.7f}, alt {h['alt']:.1f} m AMSL")
    lines.append("modes       " + (", ".join(f"{m} {d:.1f} s" for m, d in info["mode_durations_s"].items())
                                   or "none logged"))
    for m in info["modes"]:
        lines.append(f"            {m['start_s']:7.1f} - {m['end_s']:7.1f} s  {m['mode']}")
    t = info["trajectory"]
    ext = t["extent_m"]
    lines.append(f"trajectory  {t['points']} points of 0.5 s from {t['samples']} samples; extent north "
                 f"{ext['x'][0]:.1f}..{ext['x'][1]:.1f} m, east {ext['y'][0]:.1f}..{ext['y'][1]:.1f} m, "
                 f"up {ext['z'][0]:.1f}..{ext['z'][1]:.1f} m")
    if info["mission_segment"]:
        s = info["mission_segment"]
        lines.append(f"segment     {s['mode']}: {s['points']} points, {s['duration_s']:.1f} s")
    if info["mission"] is None:
        lines.append("mission     none in the log")
    else:
        items = info["mission"]["items"]
        lines.append(f"mission     {len(items)} items (x north, y east, z up from home)")
        for i, it in enumerate(items, start=1):
            if "x" in it:
                lines.append(f"  {i:2d} {it['command']:<17} x {it['x']:7.1f}  y {it['y']:7.1f}  z {it['z']:5.1f} m"
                             f"  ({it['distance_m']:.1f} m from home)")
            else:
                lines.append(f"  {i:2d} {it['command']}" + (f" {it['speed']:g} m/s" if "speed" in it else ""))
        for s in info["mission"]["skipped"]:
            lines.append(f"     skipped: {s}")
    params = info["params"]
    lines.append(f"parameters  {info['param_count']} in the log" + ("; key ones:" if params else ""))
    for k, v in params.items():
        lines.append(f"  {k:<16}{v:g}")
    if info.get("plot"):
        lines.append(f"plot        {info['plot']}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Read the log, print its summary (text or JSON) and write the plot."""
    from .. import data_path
    from ..logs import read_flight
    from .options import check_writable

    if args.log is None:
        args.log = data_path("case0.ulg")
    out = None
    if not args.no_plot:  # the plot's path is checked before the log is read
        folder = check_writable(args.out or Path.cwd(), "--out", "folder")
        out = check_writable(folder / (Path(args.log).stem + ".png"), "--out", "file", (".png",))
    flight = read_flight(args.log)
    info = summary(flight)
    if out is not None:
        from ..logs.plots import plot_flight

        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            plot_flight(flight, out)
        except OSError as err:
            raise SurrealistError(f"{out}: cannot write the plot ({err.strerror or err})") from err
        info["plot"] = os.path.abspath(out)
    print(json.dumps(info, indent=2) if args.json else _text(info))
    return 0
