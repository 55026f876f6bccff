"""The flux maps at standstill, host side (issue 25 procedure c,
firmware/app/proc_fmap.c, docs/commissioning.md "Flux maps at standstill"):
the points the procedure published (the SIL summary's commission record,
or the same results read over CAN) assembled into the project's map blob
with its MTPA / MTPV tables, compared against the plant's map.

Each point: result [0] psi_d, [1] psi_q [Vs] at the measured [2] i_d,
[3] i_q [A], the reference [4] i_d, [5] i_q, [7] the phase (1 + k nd + j)
whose results these are. The grid: i_d = -I .. I (nd points), i_q = 0 .. I
(nq points), the points within |i| <= I measured.

Assembly: each point moved from its measured current to the grid's by the
incremental inductances of the measured grid (a first-order step); the
corners beyond the current circle extrapolated linearly (along i_d where the
row has two points, else along i_q from the rows below); i_q < 0 by the
symmetry psi_d(i_d, -i_q) = psi_d(i_d, i_q), psi_q(i_d, -i_q) =
-psi_q(i_d, i_q) (docs/flux-maps.md, --mirror).

Errors against the truth (the plant's map, bicubic as the plant
interpolates it), over the identified range (the measured points and the
assembled map's grid points within the circle): |psi - psi_true| (the
vector) over the largest |psi_true| in that range, rms and worst; the MTPA:
at each current amplitude a <= i_max the angle that maximises the
identified map's torque, and the true map's torque there over the true
maximum (1 - that: the torque-per-ampere loss).

    python -m fluxdrive.commission_map SUMMARY.json --scenario SCEN.json [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .fluxmap import blob
from .fluxmap.model import FluxMap

REPO = Path(__file__).resolve().parents[3]


@dataclass
class Point:
    phase: int
    psi_d: float
    psi_q: float
    i_d: float
    i_q: float
    id_ref: float
    iq_ref: float


def points_of(record: dict, lambda_m: float = 0.0) -> list[Point]:
    """The procedure's points from a summary's commission record (fmap):
    those whose result[7] names their phase, once each. lambda_m: the PM
    flux to add to psi_d (standstill cannot see the flux at zero current:
    procedure f's result, when the drive's parameter lambda_m was not set
    to it while the procedure ran)."""
    out: dict[int, Point] = {}
    rows = list(record.get("points", [])) + [[0] + list(record.get("result", []))]
    for row in rows:
        r = row[1:]
        if len(r) < 8:
            continue
        ph = int(round(r[7]))
        if ph <= 0 or not all(np.isfinite(r)):
            continue
        out[ph] = Point(ph, r[0] + lambda_m, r[1], r[2], r[3], r[4], r[5])
    return [out[k] for k in sorted(out)]


def _grid_of(points: list[Point], nd: int, nq: int):
    i_range = max(max(abs(p.id_ref), abs(p.iq_ref)) for p in points)
    i_d = np.linspace(-i_range, i_range, nd)
    i_q = np.linspace(0.0, i_range, nq)
    return i_d, i_q, i_range


def assemble(points: list[Point], nd: int, nq: int, pole_pairs: int,
             name: str = "identified") -> tuple[FluxMap, np.ndarray]:
    """The identified map (both signs of i_q) and the mask of the measured
    grid points (nq, nd) of its i_q >= 0 half."""
    i_d, i_q, _ = _grid_of(points, nd, nq)
    pd = np.full((nq, nd), np.nan)
    pq = np.full((nq, nd), np.nan)
    di = np.zeros((nq, nd, 2))
    for p in points:
        j, k = (p.phase - 1) % nd, (p.phase - 1) // nd
        if k >= nq:
            continue
        pd[k, j], pq[k, j] = p.psi_d, p.psi_q
        di[k, j] = (i_d[j] - p.i_d, i_q[k] - p.i_q)
    measured = np.isfinite(pd)
    if measured.sum() < 4:
        raise ValueError(f"{measured.sum()} points: too few for a map")
    # the step to the grid's current: l = d psi / d i (central differences
    # where both neighbours were measured, one-sided else)
    for a in (pd, pq):
        g_d = np.zeros_like(a)
        g_q = np.zeros_like(a)
        for k in range(nq):
            for j in range(nd):
                if not measured[k, j]:
                    continue
                g_d[k, j] = _slope(a[k, :], measured[k, :], j, i_d[1] - i_d[0])
                g_q[k, j] = _slope(a[:, j], measured[:, j], k, i_q[1] - i_q[0])
        a += np.where(measured, g_d * di[..., 0] + g_q * di[..., 1], 0.0)
    # psi_q(i_d, 0) = 0 (the symmetry): the row at i_q = 0 exactly
    pq[0, measured[0]] = 0.0
    for a in (pd, pq):
        _fill(a, measured)
    full_q = np.concatenate([-i_q[:0:-1], i_q])
    psi_d = np.concatenate([pd[:0:-1], pd])
    psi_q = np.concatenate([-pq[:0:-1], pq])
    return FluxMap(i_d, full_q, psi_d, psi_q, pole_pairs, name,
                   ["identified at standstill (fmap)"]), measured


def _slope(v, ok, j, h):
    n = len(v)
    if 0 < j < n - 1 and ok[j - 1] and ok[j + 1]:
        return (v[j + 1] - v[j - 1]) / (2 * h)
    if j + 1 < n and ok[j + 1]:
        return (v[j + 1] - v[j]) / h
    if j > 0 and ok[j - 1]:
        return (v[j] - v[j - 1]) / h
    return 0.0


def _fill(a: np.ndarray, measured: np.ndarray) -> None:
    """The grid points beyond the circle: linear extrapolation along i_d in
    a row with two measured points, else along i_q from the rows below."""
    nq, nd = a.shape
    for k in range(nq):
        idx = np.flatnonzero(measured[k])
        if len(idx) >= 2:
            j0, j1 = idx[0], idx[-1]
            for j in range(0, j0):
                a[k, j] = a[k, j0] + (j - j0) * (a[k, j0 + 1] - a[k, j0])
            for j in range(j1 + 1, nd):
                a[k, j] = a[k, j1] + (j - j1) * (a[k, j1] - a[k, j1 - 1])
        else:
            for j in range(nd):
                if not measured[k, j]:
                    a[k, j] = 2 * a[k - 1, j] - a[k - 2, j]


def truth_of(scenario: dict, base: Path) -> FluxMap:
    """The plant's map of a scenario (preset or map file)."""
    mach = scenario.get("machine", {})
    if "map" in mach:
        path = Path(mach["map"])
        path = path if path.is_absolute() else (base / path if (base / path).exists()
                                                else REPO / path)
    else:
        pre = mach.get("preset", "")
        path = REPO / "maps" / (f"{pre}.fdmap" if pre != "pmasyr_file" else "pmasyr_file.npz")
    if path.suffix == ".fdmap":
        b = blob.read(path)
        return FluxMap(b["i_d"].astype(float), b["i_q"].astype(float),
                       b["psi_d"].astype(float), b["psi_q"].astype(float),
                       int(round(b["pole_pairs"])), path.stem)
    from .fluxmap import io
    return io.load(path, pole_pairs=mach.get("pole_pairs"))


def errors(ident: FluxMap, measured: np.ndarray, points: list[Point], truth: FluxMap,
           i_max: float) -> dict:
    """The errors of the identified points and map, and the MTPA's."""
    pi_d = np.array([p.i_d for p in points])
    pi_q = np.array([p.i_q for p in points])
    td, tq = truth.flux_smooth(pi_d, pi_q)
    e_pts = np.hypot(np.array([p.psi_d for p in points]) - td,
                     np.array([p.psi_q for p in points]) - tq)
    nq = measured.shape[0]
    gd, gq = np.meshgrid(ident.i_d, ident.i_q[nq - 1:])
    gd, gq = gd[measured], gq[measured]
    md, mq = ident.flux(gd, gq)
    Td, Tq = truth.flux_smooth(gd, gq)
    scale = max(np.max(np.hypot(td, tq)), np.max(np.hypot(Td, Tq)))
    e_map = np.hypot(md - Td, mq - Tq)
    # MTPA: i_d = a cos g, i_q = a sin g, g in [pi/2 - 0.3, pi] (fluxdrive's
    # frame: i_d <= 0 on MTPA but for a nearly isotropic PM machine)
    amps = np.linspace(i_max / 20, i_max, 20)
    gam = np.linspace(0.5 * np.pi - 0.3, np.pi, 1501)
    loss = []
    for a in amps:
        cd, cq = a * np.cos(gam), a * np.sin(gam)
        t_id = ident.torque_smooth(cd, cq)
        t_tr = truth.torque_smooth(cd, cq)
        g = np.argmax(t_id)
        loss.append(1.0 - t_tr[g] / np.max(t_tr))
    return {"points": len(points), "scale": float(scale),
            "points_rms": float(np.sqrt(np.mean(e_pts ** 2)) / scale),
            "points_worst": float(np.max(e_pts) / scale),
            "map_rms": float(np.sqrt(np.mean(e_map ** 2)) / scale),
            "map_worst": float(np.max(e_map) / scale),
            "mtpa_loss_worst": float(np.max(loss)),
            "mtpa_amps": [float(a) for a in amps], "mtpa_loss": [float(x) for x in loss]}


def plot(ident: FluxMap, truth: FluxMap, i_max: float, path: Path) -> None:
    """Contours of the identified map against the truth, with each's MTPA."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from .fluxmap.luts import tables
    fig, axs = plt.subplots(1, 2, figsize=(11, 4.5))
    gd, gq = np.meshgrid(np.linspace(-i_max, i_max, 81), np.linspace(-i_max, i_max, 81))
    for ax, k, lab in ((axs[0], 0, "psi_d"), (axs[1], 1, "psi_q")):
        t = truth.flux_smooth(gd, gq)[k]
        m = ident.flux_smooth(gd, gq)[k]
        lv = np.linspace(np.min(t), np.max(t), 13)
        ax.contour(gd, gq, t, lv, colors="k", linewidths=0.8)
        ax.contour(gd, gq, m, lv, colors="r", linestyles="--", linewidths=0.8)
        for mp, col, name in ((truth, "k", "MTPA true"), (ident, "r", "MTPA identified")):
            tb = tables(mp)
            ax.plot(tb.mtpa_id, tb.mtpa_iq, col, lw=2, label=name)
        ax.add_patch(plt.Circle((0, 0), i_max, fill=False, ls=":"))
        ax.set(xlabel="i_d [A]", ylabel="i_q [A]", title=f"{lab}: true (black), identified (red)",
               xlim=(-i_max, i_max), ylim=(-i_max, i_max))
        ax.legend(loc="lower left", fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="fluxdrive.commission_map", description=__doc__.split("\n")[0])
    ap.add_argument("summary")
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--out", default=None, help="folder: the blob, the plot, errors.json")
    ap.add_argument("--lambda-m", type=float, default=None,
                    help="PM flux to add to psi_d [Vs] (procedure f's result; default: the "
                         "plant map's flux at zero current, the truth, for a SIL run)")
    a = ap.parse_args(argv)
    summ = json.loads(Path(a.summary).read_text())
    scen = json.loads(Path(a.scenario).read_text())
    rec = next(c for c in summ["commission"] if c["proc"] == "fmap")
    ctl = scen.get("controller", {})
    nd, nq = int(ctl.get("id_fmap_nd", 9)), int(ctl.get("id_fmap_nq", 5))
    truth = truth_of(scen, Path(a.scenario).parent)
    lam = truth.pm_flux() if a.lambda_m is None else a.lambda_m
    pts = points_of(rec, lam)
    ident, measured = assemble(pts, nd, nq, truth.pole_pairs)
    i_max = float(ctl.get("i_max", 3.5355339))
    e = errors(ident, measured, pts, truth, min(i_max, float(ctl.get("id_fmap_current", 3.5))))
    print(f"fmap: {e['points']} points, status {rec['status']}, i_peak {rec['i_peak']:.3f} A, "
          f"rotor movement {rec['move']:.4f} rad mech")
    print(f"  points vs plant: rms {100 * e['points_rms']:.2f} %, worst "
          f"{100 * e['points_worst']:.2f} % of {e['scale']:.3f} Vs")
    print(f"  map vs plant:    rms {100 * e['map_rms']:.2f} %, worst {100 * e['map_worst']:.2f} %")
    print(f"  MTPA torque per ampere lost, worst over a <= i_max: "
          f"{100 * e['mtpa_loss_worst']:.3f} %")
    if a.out:
        out = Path(a.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "identified.fdmap").write_bytes(blob.to_bytes(ident))
        (out / "errors.json").write_text(json.dumps(e, indent=1))
        plot(ident, truth, min(i_max, float(ctl.get("id_fmap_current", 3.5))),
             out / "fmap_contours.png")
        print(f"  wrote {out}/identified.fdmap, errors.json, fmap_contours.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
