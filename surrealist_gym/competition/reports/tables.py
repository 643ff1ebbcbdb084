"""Numbers as the competition's reports write them, and their CSV tables."""
from __future__ import annotations

import csv
import math
from pathlib import Path

__all__ = ["fixed", "rounded", "write_csv"]


def rounded(value, digits: int = 4):
    """``value`` rounded for a CSV cell; "" when missing or not finite."""
    return "" if value is None or not math.isfinite(value) else round(float(value), digits)


def fixed(value, digits: int = 2) -> str:
    """``value`` with ``digits`` decimals for a text table; "-" when missing or not finite."""
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def write_csv(path: Path, rows: list[dict]) -> None:
    """Write dict rows (the first row's keys the header) as a CSV file."""
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
