"""Markdown helpers shared by the reports of the evaluation."""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["markdown_table", "pct"]


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A markdown table; floats are printed with 3 significant digits."""
    cells = [[str(h) for h in header]]
    cells += [[f"{c:.3g}" if isinstance(c, float) else str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = [
        "| " + " | ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) + " |" for r in cells
    ]
    lines.insert(1, "|" + "|".join("-" * (w + 2) for w in widths) + "|")
    return "\n".join(lines)


def pct(x: float) -> str:
    """A share as a percentage with one decimal."""
    return "–" if math.isnan(x) else f"{100 * x:.1f} %"
