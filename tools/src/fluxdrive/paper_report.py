"""What the paper reproductions (`fluxdrive rubino2020`, `fluxdrive
varatharajan2022`, `fluxdrive fabbri2022`) share: a SIL run of a scenario
given as a dict, a figure of stacked axes, and the replacement of a
generated table between two markers of a docs page."""

from __future__ import annotations

from dataclasses import dataclass
import json
import os
from pathlib import Path
import subprocess
import sys

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


@dataclass
class Run:
    scenario: dict
    log: np.ndarray
    summary: dict


def run(sil: Path, scenario: dict, out: Path, name: str) -> Run:
    out.mkdir(parents=True, exist_ok=True)
    sc_path = out / f"{name}.json"
    sc_path.write_text(json.dumps(scenario, indent=1))
    log_path = out / f"{name}.npy"
    # a map file (.npz) goes through `fluxdrive map convert`: with this
    # interpreter unless the caller names one
    env = dict(os.environ)
    env.setdefault("FLUXDRIVE_PYTHON", sys.executable)
    res = subprocess.run([str(sil), str(sc_path), "--log", str(log_path), "--decimate", "1"],
                         capture_output=True, text=True, timeout=900, env=env)
    if res.returncode != 0:
        raise RuntimeError(f"{name}: fluxdrive-sil exit {res.returncode}: {res.stderr.strip()}")
    return Run(scenario, np.load(log_path), json.loads(res.stdout))


def paper_paths(args, name: str) -> tuple[Path, Path, Path, Path]:
    """(repository root, fluxdrive-sil, log directory, figure directory) of
    a paper reproduction's command line (--sil, --out, --figures; defaults
    out/<name> and docs/figures, the latter created)."""
    from .sil import find_repo_root, locate_sil

    root = find_repo_root() or Path.cwd()
    sil = locate_sil(args.sil)
    out = Path(args.out) if args.out else root / "out" / name
    figs = Path(args.figures) if args.figures else root / "docs" / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    return root, sil, out, figs
