"""PNG plots of flights and trajectories: a top view (east to the right, north up) and an altitude profile: the
figures ``surrealist inspect`` and ``surrealist simulate`` write (unless ``--no-plot``). The same top view, alone and
as an RGB array, is what an env's ``render()`` returns (:func:`top_view_image`).

matplotlib is imported inside the functions (Agg backend, no display needed), so importing this module is cheap.
Frames: trajectories and obstacles are local (x north, y east, z up, metres); the top view draws east on the
horizontal axis and north on the vertical axis, so the picture reads like a map.
"""
from __future__ import annotations

import math
import os
from typing import Mapping, Sequence

from ..errors import DependencyNotInstalled
from ..testcase import Obstacle, Shape
from ..trajectory import Trajectory

_REFERENCE_STYLE = {"color": "black", "linewidth": 2.5, "zorder": 5}
_OBSTACLE_STYLE = {"facecolor": "tab:red", "edgecolor": "darkred", "alpha": 0.35, "linewidth": 1.0}


def _axes(title: str | None, altitude: bool = True, figsize: tuple[float, float] = (12, 5.5), dpi: float = 100):
    """A figure with the top view and, if ``altitude``, the altitude profile beside it (else ``alt`` is None)."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as err:
        raise DependencyNotInstalled("plots need matplotlib: pip install matplotlib") from err
    # a bare Figure on the Agg canvas: no pyplot, no global backend switch, nothing left open
    fig = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(fig)
    if altitude:
        top, alt = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
    else:
        top, alt = fig.subplots(1, 1), None
    top.set_xlabel("east y [m]")
    top.set_ylabel("north x [m]")
    top.set_title("top view")
    top.set_aspect("equal", adjustable="datalim")
    top.grid(True, linewidth=0.3)
    if alt is not None:
        alt.set_xlabel("time [s]")
        alt.set_ylabel("altitude z [m]")
        alt.set_title("altitude profile")
        alt.grid(True, linewidth=0.3)
    if title:
        fig.suptitle(title)
    return fig, top, alt


def _draw_obstacles(top, alt, obstacles: Sequence[Obstacle]) -> None:
    from matplotlib.patches import Circle, Polygon

    for i, obs in enumerate(obstacles):
        label = "obstacle" if i == 0 else None
        if obs.shape == Shape.CYLINDER:
            top.add_patch(Circle((obs.y, obs.x), obs.l / 2, label=label, **_OBSTACLE_STYLE))
        else:
            corners = [(east, north) for north, east in obs.footprint()]
            top.add_patch(Polygon(corners, closed=True, label=label, **_OBSTACLE_STYLE))
        if alt is not None:
            alt.axhline(obs.z + obs.h, color="darkred", linestyle=":", linewidth=0.8,
                        label="obstacle top" if i == 0 else None)
    if obstacles:
        top.autoscale_view()


def _draw(top, alt, traj: Trajectory, style: Mapping) -> None:
    top.plot(traj.y, traj.x, **style)
    if alt is not None:
        alt.plot(traj.t, traj.z, **{k: v for k, v in style.items() if k != "label"})


def _legend(fig, top, alt) -> None:
    handles, labels = top.get_legend_handles_labels()
    if alt is not None:
        h2, l2 = alt.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    if labels:
        unique = dict(zip(labels, handles))
        top.legend(unique.values(), unique.keys(), loc="best", fontsize="small")
    fig.tight_layout()


def _save(fig, top, alt, path) -> None:
    _legend(fig, top, alt)
    fig.savefig(os.fspath(path), dpi=110)


def plot_trajectories(path, trajectories: Sequence[Trajectory], labels: Sequence[str] | None = None,
                      obstacles: Sequence[Obstacle] = (), title: str | None = None,
                      styles: Sequence[Mapping] | Mapping | None = None, *, reference: Trajectory | None = None,
                      reference_label: str = "reference") -> None:
    """Write a PNG with the top view and altitude profile of several trajectories.

    Args:
        path: output PNG.
        trajectories: runs to draw; thin lines when there are more than three.
        labels: one label per trajectory (None: unlabelled, except a single "run" legend entry).
        obstacles: boxes are drawn as rotated rectangles, cylinders as circles; their tops as dotted lines in
            the altitude profile.
        title: figure title.
        styles: matplotlib line keyword arguments, one mapping per trajectory or one for all.
        reference: a trajectory drawn on top as a thick black line (e.g. the real flight).
        reference_label: its legend entry.

    Example::

        plot_trajectories("runs.png", runs, obstacles=test.obstacles, reference=flight.trajectory)
    """
    fig, top, alt = _axes(title)
    _draw_trajectories(top, alt, trajectories, labels, obstacles, styles, reference, reference_label)
    _save(fig, top, alt, path)


def top_view_image(trajectories: Sequence[Trajectory], obstacles: Sequence[Obstacle] = (), title: str | None = None,
                   *, reference: Trajectory | None = None, reference_label: str = "reference",
                   size: tuple[float, float] = (6.0, 6.0), dpi: int = 80):
    """The top view of :func:`plot_trajectories` alone, as an RGB image: an H x W x 3 uint8 numpy array (H x W =
    ``size`` x ``dpi`` pixels; 480 x 480 by default), drawn on matplotlib's Agg canvas; what an env's ``render()``
    returns with ``render_mode="rgb_array"``.

    Example::

        frame = top_view_image(runs, obstacles=test.obstacles)   # frame.shape == (480, 480, 3)
    """
    import numpy as np

    fig, top, _ = _axes(title, altitude=False, figsize=size, dpi=dpi)
    _draw_trajectories(top, None, trajectories, None, obstacles, None, reference, reference_label)
    _legend(fig, top, None)
    fig.canvas.draw()
    return np.array(fig.canvas.buffer_rgba(), dtype=np.uint8)[..., :3]


def _draw_trajectories(top, alt, trajectories, labels, obstacles, styles, reference, reference_label) -> None:
    """Draw obstacles, trajectories and the reference (with its start and end) on the axes (``alt`` may be None)."""
    trajectories = list(trajectories)
    if labels is not None and len(labels) != len(trajectories):
        raise ValueError(f"plot_trajectories: {len(labels)} labels for {len(trajectories)} trajectories")
    if isinstance(styles, Mapping):
        styles = [styles] * len(trajectories)
    if styles is not None and len(styles) != len(trajectories):
        raise ValueError(f"plot_trajectories: {len(styles)} styles for {len(trajectories)} trajectories")
    _draw_obstacles(top, alt, obstacles)
    many = len(trajectories) > 3
    for i, traj in enumerate(trajectories):
        style = {"linewidth": 0.9 if many else 1.5, "alpha": 0.7 if many else 0.9}
        if labels is not None:
            style["label"] = labels[i]
        elif i == 0:
            style["label"] = "runs" if len(trajectories) > 1 else "run"
        if many and labels is None:
            style["color"] = "tab:blue"
        style.update(styles[i] if styles is not None else {})
        _draw(top, alt, traj, style)
    if reference is not None:
        _draw(top, alt, reference, {**_REFERENCE_STYLE, "label": reference_label})
        top.plot(reference.y[:1], reference.x[:1], "o", color="green", label="start", zorder=6)
        top.plot(reference.y[-1:], reference.x[-1:], "s", color="black", label="end", zorder=6)


def plot_flight(flight, path, obstacles: Sequence[Obstacle] = ()) -> None:
    """Write a PNG of a :class:`~surrealist_gym.logs.FlightLog`: its trajectory, mission items and flight modes.

    The altitude profile shades each flight-mode span. Mission items are drawn at their position relative to
    home, which for a PX4 log (home set at arming) is close to the trajectory's origin, the first position.

    Example::

        plot_flight(read_flight("case0.ulg"), "case0.png")
    """
    traj = flight.trajectory
    fig, top, alt = _axes(f"{os.path.basename(flight.path)} - {flight.vehicle_type}, {flight.duration:.1f} s")
    _draw_obstacles(top, alt, obstacles)
    _draw(top, alt, traj, {"color": "tab:blue", "linewidth": 1.8, "label": "flight"})
    top.plot(traj.y[:1], traj.x[:1], "o", color="green", label="start", zorder=6)
    top.plot(traj.y[-1:], traj.x[-1:], "s", color="black", label="end", zorder=6)
    if flight.mission is not None:
        pts = [(it, it.x, it.y) for it in flight.mission.items if it.has_position and math.isfinite(it.x)]
        if pts:
            top.plot([p[2] for p in pts], [p[1] for p in pts], "x--", color="tab:orange", linewidth=0.8,
                     markersize=9, label="mission items")
            for it, x, y in pts:
                top.annotate(it.command.name.lower(), (y, x), textcoords="offset points", xytext=(5, 5),
                             fontsize="small", color="tab:orange")
    offset = (int(flight.positions.timestamp_us[0]) - flight.start_us) / 1e6
    names = list(dict.fromkeys(s.mode for s in flight.modes))
    for span in flight.modes:
        alt.axvspan(span.start - offset, span.end - offset, alpha=0.12, linewidth=0,
                    color=f"C{names.index(span.mode) % 10}", label=span.mode)
    _save(fig, top, alt, path)
