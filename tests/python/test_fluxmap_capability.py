"""`fluxdrive capability` on a flux map (fluxmap/capability.py) against
exact references: a linear IPM machine written as a map, whose capability
is closed-form (R_s = 0: the MTPA at i_max, the current/voltage corner,
the MTPV on the voltage ellipse), and the analytic saturated model on a
fine map against a dense, independent solve of the same optimisation on
the model itself; and the voltage limit the drive applies (the board's
duty range, drive_derive / modulation_v_max)."""

from __future__ import annotations

import numpy as np
import pytest

from fluxdrive.fluxmap.capability import map_capability, v_max_of
from fluxdrive.fluxmap.model import FluxMap, syr_to_fluxdrive
from fluxdrive.fluxmap.presets import model

from conftest import REAL_SIL, REPO_ROOT

# linear IPM: p, L_d, L_q, lambda_m; i_max; v_max (characteristic current
# lambda_m / L_d = 20 A < i_max: the MTPV is reached, the speed range unbounded)
P, LD, LQ, LM = 4, 0.2e-3, 0.5e-3, 0.004
I_MAX, V_MAX = 30.0, 12.0


def linear_map(n: int = 31) -> FluxMap:
    """The linear IPM on a grid reaching beyond i_max on every side (the
    Catmull-Rom interpolant reproduces a linear function in its interior)."""
    i_d = np.linspace(-2 * I_MAX, I_MAX, n)
    i_q = np.linspace(-I_MAX, 2 * I_MAX, n)
    D, Q = np.meshgrid(i_d, i_q)
    return FluxMap(i_d, i_q, LD * D + LM, LQ * Q, P, "linear_ipm")


def exact_linear(w: float) -> float:
    """The largest torque under |i| <= I_MAX, |lambda| <= V_MAX / w (R_s = 0):
    the best admissible of the KKT candidates."""
    psi = V_MAX / w

    def torque(i_d, i_q):
        return 1.5 * P * (LM * i_q + (LD - LQ) * i_d * i_q)

    def ok(i_d, i_q):
        return (np.hypot(LD * i_d + LM, LQ * i_q) <= psi * (1 + 1e-12)
                and np.hypot(i_d, i_q) <= I_MAX * (1 + 1e-12) and i_q >= 0)

    cand = []
    dl = LQ - LD
    i_d = (LM - np.sqrt(LM ** 2 + 8 * dl ** 2 * I_MAX ** 2)) / (4 * dl)  # MTPA at i_max
    cand.append((i_d, np.sqrt(I_MAX ** 2 - i_d ** 2)))
    # circle and ellipse:
    # (L_d^2 - L_q^2) i_d^2 + 2 L_d lambda_m i_d + lambda_m^2 + L_q^2 I^2 - psi^2 = 0
    quad = [LD ** 2 - LQ ** 2, 2 * LD * LM, LM ** 2 + LQ ** 2 * I_MAX ** 2 - psi ** 2]
    for i_d in np.roots(quad):
        if abs(i_d.imag) < 1e-12 and abs(i_d.real) <= I_MAX:
            cand.append((i_d.real, np.sqrt(I_MAX ** 2 - i_d.real ** 2)))
    # MTPV on the ellipse: lambda = psi (cos d, sin d), d/dd sin d (a cos d + b) = 0
    a, b = psi * (1 / LQ - 1 / LD), LM / LD
    for c in np.roots([2 * a, b, -a]):
        if abs(c.imag) < 1e-12 and abs(c.real) <= 1:
            d = np.arccos(c.real)
            cand.append(((psi * np.cos(d) - LM) / LD, psi * np.sin(d) / LQ))
    best = [torque(*x) for x in cand if ok(*x)]
    return max(best) if best else 0.0


def test_linear_ipm_exact():
    m = linear_map()
    rpm = np.array([500, 1000, 1500, 2000, 2500, 3000, 4000, 5000, 6000, 8000, 10000, 15000])
    w = rpm * np.pi / 30 * P
    rows = map_capability(m, 0.0, I_MAX, 0.0, 0.0, 1e9, rpm * np.pi / 30, v_max=V_MAX)
    got = np.array([r[0] for r in rows])
    ref = np.array([exact_linear(x) for x in w])
    err = got / ref - 1
    print("linear IPM: rpm, exact N m, solved N m, error %, limit")
    for r, e, g, x, row in zip(rpm, ref, got, err, rows):
        print(f"  {r:6d} {e:8.4f} {g:8.4f} {100 * x:+.4f} {row[3]}")
    assert np.all(np.abs(err) < 0.005)
    # the range covers the three regions: MTPA at i_max, the corner, the MTPV
    lims = [r[3] for r in rows]
    assert lims[0] == "current" and "current+voltage" in lims and lims[-1] == "voltage"
    for (t, i_d, i_q, _), x in zip(rows, w):  # the solved currents are admissible
        assert np.hypot(i_d, i_q) <= I_MAX * (1 + 1e-9)
        assert x * np.hypot(LD * i_d + LM, LQ * i_q) <= V_MAX * (1 + 1e-9)


def fine_map(name: str, half: float, n: int) -> tuple[FluxMap, object]:
    hk, p = model(name)
    a = np.linspace(-half, half, n)
    D, Q = np.meshgrid(a, a)
    pd, pq = hk.flux(D, Q)
    i_d, i_q, pd, pq = syr_to_fluxdrive(a, a.copy(), pd, pq)
    return FluxMap(i_d, i_q, pd, pq, p, name), hk


def dense_reference(hk, p, rs, i_max, v_max, w, n=401, zoom=3):
    """The largest admissible torque on the analytic model itself: a
    Cartesian grid over the half disc, then finer grids around the best
    admissible point (no assumption on rays or monotonicity)."""
    cd, cq, h = 0.0, 0.5 * i_max, 0.5 * i_max
    best = 0.0
    for _ in range(zoom + 1):
        d = np.linspace(cd - 2 * h, cd + 2 * h, n) if _ else np.linspace(-i_max, i_max, 2 * n)
        q = np.linspace(cq - 2 * h, cq + 2 * h, n) if _ else np.linspace(0.0, i_max, n)
        D, Q = np.meshgrid(d, q)
        sp_d, sp_q = hk.flux(Q, -D)  # fluxdrive -> SyR: i_d(SyR) = i_q, i_q(SyR) = -i_d
        ld, lq = -sp_q, sp_d
        v = np.hypot(rs * D - w * lq, rs * Q + w * ld)
        t = 1.5 * p * (ld * Q - lq * D)
        t = np.where((np.hypot(D, Q) <= i_max) & (v <= v_max) & (Q >= 0), t, -np.inf)
        k = np.unravel_index(np.argmax(t), t.shape)
        best = max(best, float(t[k]))
        cd, cq = D[k], Q[k]
        h = 4 * (d[1] - d[0])
    return best


@pytest.mark.parametrize("name,half,rs,i_max,v_max,rpm", [
    ("ipm_sat", 40.0, 0.05, 30.0, 40.0, [500, 1000, 2000, 4250, 6000, 12000]),
    ("pmasyr", 10.0, 0.5, 8.0, 200.0, [1000, 2000, 4250, 6000, 12000]),
    # the scenario syr_1k1_speed_load: 650 V link, duty 0 .. 0.95, v_margin 0.95,
    # 1.5 x the rated current
    ("syr_1k1", 8.0, 6.8, 1.5 * 2.3 * np.sqrt(2), 0.95 * 0.95 * 650 / np.sqrt(3),
     [1000, 2000, 4250, 6000, 8000]),
])
def test_saturated_dense(name, half, rs, i_max, v_max, rpm):
    m, hk = fine_map(name, half, 161)
    rpm = np.array(rpm)
    rows = map_capability(m, rs, i_max, 0.0, 0.0, 1e9, rpm * np.pi / 30, v_max=v_max)
    print(f"{name}: rpm, dense reference N m, solved N m, error %, limit")
    errs = []
    for r, row in zip(rpm, rows):
        ref = dense_reference(hk, m.pole_pairs, rs, i_max, v_max, r * np.pi / 30 * m.pole_pairs)
        errs.append(row[0] / ref - 1)
        print(f"  {r:6d} {ref:8.4f} {row[0]:8.4f} {100 * errs[-1]:+.4f} {row[3]}")
    assert np.all(np.abs(errs) < 0.005)


def test_v_max_as_the_drive():
    """v_margin x the linear range of the duty range (modulation_v_max),
    narrowed by the DFC window for a star-point source (dfc_window_range)."""
    cfg = {"v_dc": 650.0, "ts": 62.5e-6,
           "board": {"duty_min": 0.0, "duty_max": 0.95},
           "controller": {"v_margin": 0.95, "pos_source": "encoder",
                          "dfc_t0": 1.5e-6, "dfc_tw": 3e-6}}
    v, how = v_max_of(cfg)
    assert v == pytest.approx(0.95 * 0.95 * 650.0 / np.sqrt(3.0), rel=1e-12)  # 338.69 V
    assert "duty 0 .. 0.95" in how
    cfg["controller"]["pos_source"] = "ivd"
    v, how = v_max_of(cfg)
    # the window: lo = max(0, 0.5 - 0.024) = 0.476, hi = min(0.95, 1 - 0.024 - 0.048) = 0.928
    assert v == pytest.approx(0.95 * (0.928 - 0.476) * 650.0 / np.sqrt(3.0), rel=1e-9)
    assert "DFC window" in how


def truncated_map() -> FluxMap:
    """The linear IPM on a grid cut at i_d = -25 A: its MTPV, from
    -lambda_m / L_d = -20 A at zero flux, leaves the grid as the flux grows."""
    i_d = np.linspace(-25.0, 15.0, 161)
    i_q = np.linspace(0.0, 60.0, 241)
    D, Q = np.meshgrid(i_d, i_q)
    return FluxMap(i_d, i_q, LD * D + LM, LQ * Q, P, "linear_ipm_cut")


def exact_mtpv_row(m: FluxMap, lam: float) -> tuple[float, bool, float]:
    """The largest torque at flux amplitude lam over the currents inside the
    grid, closed-form: the stationary points over the load angle (the MTPV)
    and the ends of the arcs inside the grid (the flux circle crossing the
    grid's edges). Returns the torque, whether an edge gives it, its i_d."""
    def cur(d):
        return (lam * np.cos(d) - LM) / LD, lam * np.sin(d) / LQ

    def inside(i_d, i_q):
        e = 1e-9
        return m.i_d[0] - e <= i_d <= m.i_d[-1] + e and -e <= i_q <= m.i_q[-1] + e

    cand = []
    a, b = lam * (1 / LQ - 1 / LD), LM / LD  # d/dd sin d (a cos d + b) = 0
    for c in np.roots([2 * a, b, -a]):
        if abs(c.imag) < 1e-12 and abs(c.real) <= 1:
            cand.append((*cur(np.arccos(c.real)), False))
    for i_d in (m.i_d[0], m.i_d[-1]):  # lambda_q = +sqrt(lam^2 - lambda_d^2)
        r = lam ** 2 - (LD * i_d + LM) ** 2
        if r >= 0:
            cand.append((i_d, np.sqrt(r) / LQ, True))
    for i_q in (m.i_q[-1],):
        r = lam ** 2 - (LQ * i_q) ** 2
        if r >= 0:
            for s in (-1, 1):
                cand.append(((s * np.sqrt(r) - LM) / LD, i_q, True))
    best = (0.0, False, 0.0)
    for i_d, i_q, edge in cand:
        t = 1.5 * P * (LM * i_q + (LD - LQ) * i_d * i_q)
        if inside(i_d, i_q) and t > best[0]:
            best = (t, edge, i_d)
    return best


def test_mtpv_edge_refined_and_labelled():
    """Issue 23 point 15: where the true MTPV lies beyond the grid the table
    is the map-edge limit, on the edge itself (not up to 0.8 A inside it),
    and labelled so (tables, map check's summary)."""
    from fluxdrive.fluxmap.luts import edge_ranges, tables
    from fluxdrive.fluxmap.summary import describe

    m = truncated_map()
    t = tables(m)
    ll = np.linspace(0.0, t.mtpv_flux_max, len(t.mtpv_torque))
    rows = [exact_mtpv_row(m, x) for x in ll]
    # the table is the largest torque at a flux not above lambda (monotone):
    # its rows where the circle's own maximum is not that (the grid's far
    # corner, where the circle leaves the grid) hold the running maximum
    run = np.maximum.accumulate([r[0] for r in rows])
    worst_t, worst_id, n_edge, n_in = 0.0, 0.0, 0, 0
    for k in range(1, len(ll)):
        ref, edge, i_d = rows[k]
        if ref < run[k] or ref <= 0:
            assert t.mtpv_torque[k] == pytest.approx(run[k], rel=1e-3, abs=1e-9)
            continue
        assert bool(t.mtpv_edge[k]) == edge, (k, ll[k])
        worst_t = max(worst_t, abs(t.mtpv_torque[k] / ref - 1))
        if edge:
            n_edge += 1
            worst_id = max(worst_id, abs(t.mtpv_id[k] - i_d))
        else:
            n_in += 1
    print(f"truncated linear IPM: {n_edge} MTPV rows on the grid's edge, {n_in} inside, "
          f"worst |i_d - edge| {worst_id:.2e} A, worst torque error {100 * worst_t:.4f} %; "
          f"edge ranges {edge_ranges(t)}")
    assert n_edge >= 20 and n_in >= 5  # both kinds of rows are exercised
    assert worst_id < 1e-3  # on the edge (was 0.01-0.8 A inside)
    assert worst_t < 1e-3  # exact at the edge; the interpolant's edge cells elsewhere
    text = describe(m)
    print(text)
    assert "map-edge limit" in text and "true MTPV lies outside the grid" in text


@pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")
def test_capability_command_on_the_scenario(capsys):
    """`fluxdrive capability` on the flux-map scenario takes the drive's
    voltage limit from the scenario (board duty 0 .. 0.95, v_margin 0.95,
    650 V: 338.69 V) and agrees with a dense solve at that limit."""
    from argparse import Namespace

    from fluxdrive.capability import main_capability

    scen = str(REPO_ROOT / "sil" / "scenarios" / "syr_1k1_speed_load.json")
    rc = main_capability(Namespace(sil=str(REAL_SIL), scenario=scen, min_rpm=2000, max_rpm=6000,
                                   points=3))
    out = capsys.readouterr().out
    print(out)
    assert rc == 0
    v = 0.95 * 0.95 * 650.0 / np.sqrt(3.0)
    assert f"v_max {v:.2f} V" in out and "board duty 0 .. 0.95" in out
    got = [float(line.split()[1]) for line in out.splitlines()[3:6]]
    hk, p = model("syr_1k1")
    for rpm, t in zip((2000, 4000, 6000), got):
        ref = dense_reference(hk, p, 6.8, 1.5 * 2.3 * np.sqrt(2), v, rpm * np.pi / 30 * p)
        # the committed map's 0.5 A grid against the model itself
        print(f"  {rpm} rpm: command {t:.3f} N m, dense solve on the model {ref:.4f} N m, "
              f"{100 * (t / ref - 1):+.2f} %")
        assert t == pytest.approx(ref, rel=0.005), rpm
