"""A picture of how well a surrogate predicts: predicted vs true values with the predicted spread, and the
calibration of that spread.

Left panel: each evaluation at (true, predicted) on the target's scale, with a bar over the predicted mean +/- one
standard deviation (computed on the modelled scale, then mapped back, so the bars of a log-scale model are
asymmetric, and both axes are symmetric-log); the diagonal is a perfect prediction. Right panel: for each nominal
central coverage p of a Gaussian with the predicted mean and sd, the share of true values inside that interval; a
calibrated model follows the diagonal, one below it is over-confident (sd too narrow), one above it too cautious.
matplotlib is imported inside the function (Agg canvas, no display).
"""
from __future__ import annotations

from pathlib import Path
from statistics import NormalDist

import numpy as np

from surrealist_gym.errors import DependencyNotInstalled

from .models import Predictions, SurrogateModel


def plot_predictions(path, model: SurrogateModel, predicted: Predictions, title: str | None = None) -> Path:
    """Write the two-panel PNG of ``model``'s predictions (``predict_dataset(model, dataset)``) to ``path``;
    returns the path."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as err:
        raise DependencyNotInstalled("plots need matplotlib: pip install matplotlib") from err
    y, pred, low, high, z = predicted.true, predicted.mean, predicted.low, predicted.high, predicted.z
    metrics = predicted.metrics()

    fig = Figure(figsize=(11, 5))
    FigureCanvasAgg(fig)
    scatter, calibration = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.3, 1]})
    scatter.errorbar(y, pred, yerr=[pred - low, high - pred], fmt="o", markersize=3, elinewidth=0.6, alpha=0.6)
    span = [float(min(y.min(), pred.min())), float(max(y.max(), pred.max()))]
    scatter.plot(span, span, color="black", linewidth=1, label="perfect prediction")
    if model.log_scale:  # as the model sees it: the long tail of bad values compressed (all values < 0)
        scatter.set_xscale("symlog", linthresh=1.0)
        scatter.set_yscale("symlog", linthresh=1.0)
        limits = (span[0] * 1.3, min(span[1] * 0.7, -0.5))
    else:
        pad = 0.05 * (span[1] - span[0]) or 1.0
        limits = (span[0] - pad, span[1] + pad)
    scatter.set(xlim=limits, ylim=limits,  # a wide bar may leave the frame; the points never do
                xlabel=f"true {model.target}", ylabel=f"predicted {model.target} (mean +/- 1 sd)",
                title=f"{metrics['n']} evaluations: Spearman {metrics['spearman']:.3f}, R2 {metrics['r2']:.3f}")

    nominal = np.linspace(0.0, 1.0, 41)
    observed = [(z <= NormalDist().inv_cdf(0.5 + p / 2)).mean() if p < 1 else 1.0 for p in nominal]
    calibration.plot(nominal, observed, marker=".", label=f"{model.kind}")
    calibration.plot([0, 1], [0, 1], color="black", linewidth=1, label="calibrated")
    calibration.set(xlabel="nominal coverage of the central interval", ylabel="share of true values inside",
                    title=f"uncertainty: {metrics['within_1sd']:.0%} within 1 sd (68% ideal)", aspect="equal")
    for ax in (scatter, calibration):
        ax.legend(loc="upper left")
        ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path
