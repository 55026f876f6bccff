"""Plotting SIL logs to PNG, headless (Agg canvas, no pyplot global state)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from fluxdrive.errors import FluxdriveError
from fluxdrive.logs import DISCRETE_SIGNALS, TIME, check_signals, label_of, unit_of

#: Above this many samples per line, plot a strided view (visual only).
MAX_POINTS = 200_000


def _ylabel(group: list[str]) -> str:
    units = list(dict.fromkeys(unit_of(n) for n in group))
    if len(units) == 1:
        u = units[0]
        names = ", ".join(group)
        return f"{names} [{u}]" if u else names
    return ", ".join(f"[{u}]" if u else "[-]" for u in units)


def plot_log(
    log: np.ndarray,
    groups: list[list[str]],
    out: str | Path,
    title: str | None = None,
    dpi: int = 110,
) -> Path:
    """Draw one subplot per group on a shared time axis and save a PNG."""
    check_signals(log, groups)
    out = Path(out)
    t = np.asarray(log[TIME], dtype=float)
    stride = max(1, int(np.ceil(t.size / MAX_POINTS)))
    n = len(groups)
    fig = Figure(figsize=(10, 2.6 * n + 0.8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for ax, group in zip(axes, groups):
        mixed = len({unit_of(s) for s in group}) > 1
        for name in group:
            y = np.asarray(log[name], dtype=float)
            style = "steps-post" if name in DISCRETE_SIGNALS else "default"
            ax.plot(
                t[::stride],
                y[::stride],
                label=label_of(name) if mixed else name,
                drawstyle=style,
                linewidth=1.0,
            )
        ax.set_ylabel(_ylabel(group))
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel("t [s]")
    if t.size and np.isfinite(t[[0, -1]]).all():
        if t[-1] > t[0]:
            axes[-1].set_xlim(t[0], t[-1])
    if title:
        fig.suptitle(title)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(out, dpi=dpi, format="png")
    except OSError as exc:
        raise FluxdriveError(f"cannot write plot {out}: {exc}") from None
    return out
