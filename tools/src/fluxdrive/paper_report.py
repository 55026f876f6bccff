"""What the paper reproductions (`fluxdrive rubino2020`, `fluxdrive
varatharajan2022`) share: a figure of stacked axes, and the replacement of
a generated table between two markers of a docs page."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def stacked_axes(rows: int, title: str, width: float = 8.0):
    """matplotlib (Agg), a figure of `rows` axes sharing x: (plt, fig, axes)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    f, ax = plt.subplots(rows, 1, figsize=(width, 2.2 * rows), sharex=True)
    f.suptitle(title, fontsize=10)
    return plt, f, np.atleast_1d(ax)


def replace_table(doc: Path, tag: str, table: str) -> bool:
    """Puts `table` between `<!-- {tag}:begin -->` and `<!-- {tag}:end -->`
    of `doc` (kept as is when the markers are missing). True when written."""
    text = doc.read_text()
    a, b = f"<!-- {tag}:begin -->", f"<!-- {tag}:end -->"
    if a not in text or b not in text:
        return False
    text = text[:text.index(a) + len(a)] + "\n" + table + "\n" + text[text.index(b):]
    doc.write_text(text)
    return True
