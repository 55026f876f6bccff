"""Figures of a flux map (fluxdrive frame): flux-linkage families,
incremental inductances, and the (i_d, i_q) plane with constant-torque
contours, MTPA, MTPV, current-limit circles and voltage-limit curves."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .luts import tables  # noqa: E402
from .model import FluxMap  # noqa: E402

META = {"Software": None}  # no version string in the files


def _fluxes(m: FluxMap, path: Path) -> None:
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for iq in np.linspace(0, m.i_q[-1], 5):
        ax[0].plot(m.i_d, m.flux(m.i_d, np.full_like(m.i_d, iq))[0], label=f"i_q = {iq:g} A")
    for i_d in np.linspace(m.i_d[0], min(m.i_d[-1], 0.0), 5):
        ax[1].plot(m.i_q, m.flux(np.full_like(m.i_q, i_d), m.i_q)[1], label=f"i_d = {i_d:g} A")
    ax[0].set(xlabel="i_d [A]", ylabel="lambda_d [Vs]", title="d axis (cross-saturation: i_q)")
    ax[1].set(xlabel="i_q [A]", ylabel="lambda_q [Vs]", title="q axis (cross-saturation: i_d)")
    for a in ax:
        a.grid(True)
        a.legend(fontsize=7)
    fig.suptitle(f"{m.name}: flux linkages (fluxdrive frame)")
    fig.tight_layout()
    fig.savefig(path, dpi=90, metadata=META)
    plt.close(fig)


def _inductances(m: FluxMap, path: Path) -> None:
    D, Q = np.meshgrid(np.linspace(m.i_d[0], m.i_d[-1], 81), np.linspace(m.i_q[0], m.i_q[-1], 81))
    l = m.inductance(D, Q)
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.8))
    for a, z, t in zip(ax, (l[0], l[3], l[1]), ("l_dd", "l_qq", "l_dq")):
        c = a.contourf(D, Q, z * 1e3, 20)
        fig.colorbar(c, ax=a, label="mH")
        a.set(xlabel="i_d [A]", ylabel="i_q [A]", title=f"{t} (25)")
    fig.suptitle(f"{m.name}: incremental inductances")
    fig.tight_layout()
    fig.savefig(path, dpi=90, metadata=META)
    plt.close(fig)


def _plane(m: FluxMap, path: Path, v_dc: float | None, i_limit: float | None) -> None:
    t = tables(m)
    D, Q = np.meshgrid(np.linspace(m.i_d[0], m.i_d[-1], 161), np.linspace(0, m.i_q[-1], 81))
    fig, ax = plt.subplots(figsize=(7, 5))
    c = ax.contour(D, Q, m.torque_smooth(D, Q), 12, cmap="viridis", linewidths=0.8)
    ax.clabel(c, fontsize=7, fmt="%.1f N m")
    ax.plot(t.amp_id, t.amp_iq, "r", lw=2, label="MTPA")
    ok = np.isfinite(t.mtpv_id) & (t.mtpv_iq > 0)
    e = t.mtpv_edge if t.mtpv_edge is not None else np.zeros_like(ok)
    if np.any(ok & ~e):
        ax.plot(np.where(ok & ~e, t.mtpv_id, np.nan), np.where(ok & ~e, t.mtpv_iq, np.nan), "m--",
                lw=2, label="MTPV")
    if np.any(ok & e):  # the table where the map's edge limits it (the true MTPV is outside)
        ax.plot(t.mtpv_id[ok & e], t.mtpv_iq[ok & e], "mx", ms=4,
                label="MTPV table: the map-edge limit (true MTPV outside the grid)")
    g = np.linspace(0, np.pi, 200)
    for a in [x for x in (i_limit, 1.5 * i_limit if i_limit else None) if x]:
        ax.plot(a * np.cos(g), a * np.sin(g), "k:", lw=1)
        ax.annotate(f"|i| = {a:.2f} A", (0, a), fontsize=7)
    if v_dc:
        pd, pq = m.flux_smooth(D, Q)
        lam = np.hypot(pd, pq)
        levels = sorted({round(x, 3) for x in (0.5 * lam.max(), 0.75 * lam.max())})
        cs = ax.contour(D, Q, lam, levels, colors="tab:orange", linewidths=1.2)
        speeds = [v_dc / np.sqrt(3) / lv / m.pole_pairs * 30 / np.pi for lv in levels]
        ax.clabel(cs, fontsize=7, fmt={lv: f"{s:.0f} rpm" for lv, s in zip(levels, speeds)})
        ax.plot([], [], color="tab:orange", label=f"voltage limit at {v_dc:g} V DC (Rs neglected)")
    ax.set(xlabel="i_d [A]", ylabel="i_q [A]", title=f"{m.name}: the (i_d, i_q) plane",
           xlim=(m.i_d[0], m.i_d[-1]), ylim=(0, m.i_q[-1]))
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=90, metadata=META)
    plt.close(fig)


def plot_all(m: FluxMap, out: Path, v_dc: float | None = None,
             i_limit: float | None = None) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / f"map_{m.name}_{k}.png" for k in ("flux", "inductance", "plane")]
    _fluxes(m, paths[0])
    _inductances(m, paths[1])
    _plane(m, paths[2], v_dc, i_limit)
    return paths
