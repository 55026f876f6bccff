"""Random machines within physical ranges (issue 23, point 19; docs/machines.md).

A seeded, reproducible generator: `draw(kind, seed)` gives the same machine
for the same (kind, seed) on every platform (numpy's PCG64 seeded with
[seed, kind index]). Each draw is a scenario's `machine`, `controller`,
`dc_link`, `mechanics` and `sensors` sections (docs/scenarios.md) that the
SIL and the drive's validation accept (firmware/app/drive_config.c), plus
the rated figures the tests derive their limits from.

The ranges, per unit of the voltage the drive can apply at the rated point
v_s = v_margin * duty span * v_dc / sqrt(3) (0.95 * 0.95 * v_dc / sqrt 3 on
the default g474_nucleo board), and why:

* v_dc in {24, 48, 310, 540} V: the supply classes of the boards (battery
  24 / 48 V, rectified 230 V and 400 V mains).
* pole pairs 1 .. 24 (servo motors 2-5, traction 4-8, hub motors up to 23 as
  Fabbri's e-bike), rated speed 300 .. 6000 rpm, with the rated electrical
  frequency at most f_pwm / 20 (800 Hz at 16 kHz): at least 20 samples per
  electrical period for the sampled current control (a redraw beyond).
* back-EMF at rated speed e = w_e lambda_m / v_s in [0.4, 0.75]: below the
  link voltage with room for R_s i and the inductive drop (the rated point
  must lie inside the voltage limit; checked below).
* synchronous reactance x = w_e L_q i_n / v_s in [0.1, 0.5] (SPM: small
  armature reaction, characteristic current beyond rated) and
  [0.3, 0.9] for IPM with saliency L_q / L_d in [1.5, 3] (interior-PM rotors;
  larger ratios are SyR machines, drawn as maps).
* R_s from r = R_s i_n / v_s in [0.005, 0.08]: copper drop 0.5-8 % of the
  voltage at the rated point (large to small machines).
* rated current (peak) log-uniform in [2, 40] A at 24 / 48 V, [1, 15] A on
  the mains links (the ADC ranges of the boards, 2.5 i_trip).
* inertia from the mechanical time constant J w_m,n / T_n in [0.02, 0.5] s
  (servo to small industrial drives); viscous friction 1 % of T_n at rated
  speed.
* the rated point (MTPA at i_n, rated speed) needs at most 0.95 v_s
  (w_e |psi| + R_s i_n): else redrawn.

Saturated maps (`syr_map`, `pmsyr_map`): the Hinkkanen 2017 model of
fluxmap/analytic.py with the 5.5 kW example's coefficients scaled as the
syr_1k1 preset (fluxmap/presets.py): in current by k log-uniform in
[0.05, 1] (0.3 to 6 kW), in flux by c in [0.7, 2.5], the minimum-inductance
axis by r in [2, 4] (saliency); PM-SyR with a PM flux of 10-30 % of the rated
flux. Rated current: k * 23.7 A (the preset's rated current per unit k)
times [0.7, 1.2]; the grid reaches 1.5 times it, so i_max lies inside the map.
Rated speed from the voltage: w_e |psi_n| = 0.8 v_s.

Star-point machines (`star`, Fabbri 2022): anisotropy p = (L_d - L_q) /
(L_d + L_q) of either sign with 0.1 <= |p| <= 0.45 (Theorem 1 needs |p| < 1/2;
below 0.1 the 2theta term vanishes in the noise), (L_d + L_q)/2 in
[100, 1000] uH, the zero-sequence mutual M0 in [0, 0.15] (L_d + L_q)
(docs/dfc.md: (-1/6, 1/6]), the split of the 2theta terms by the DFC
signal's amplitude |L2 - M2| in [0.1, 0.3] L0 of either sign (Table 5.1:
-0.14, Fig. 3.3: +0.21; L2 + 2 M2 = L_d - L_q fixes the rest; near 0 the
star point carries no position: a first version drew M2 = k (L_d - L_q),
which crosses it at k = 1/3, and the IVD of such a draw stalled at 113 mrad),
R_s 0.1 .. 3 Ohm, pole pairs 2 .. 12, star
noise 0 .. 0.06 V (the range of issue 23's start-up grid), 24 V.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import FluxdriveError

KINDS = ("spm", "ipm", "syr_map", "pmsyr_map", "star")
SQRT3 = math.sqrt(3.0)
RPM = math.pi / 30.0
F_PWM = 16000.0
V_MARGIN = 0.95  # the drive's default
DUTY_SPAN = 0.95  # g474_nucleo: duty 0 .. 0.95
CURRENT_BW = 2000.0  # rad/s: the presets keep the table's default
MAX_TRIES = 200
# syr_1k1: rated 2.3 sqrt 2 A at k = SYR_K: the rated current per unit k
I_PER_K = 2.3 * math.sqrt(2.0) / 0.137396
REF_FLUX_PER_C = 0.465  # syr_1k1: about 0.93 Vs rated flux at c = 2


def v_s(v_dc: float) -> float:
    """The voltage amplitude the drive applies: v_margin * duty span * v_dc / sqrt 3."""
    return V_MARGIN * DUTY_SPAN * v_dc / SQRT3


@dataclass
class Drawn:
    kind: str
    seed: int
    tries: int
    sections: dict  # scenario sections
    rated: dict  # i_n (peak), t_n, n_rpm, v_dc, ...
    model: object = None  # analytic map model (Hinkkanen), maps only
    grid: tuple = field(default=())  # (half-width A, points) of the map grid

    def params_line(self) -> str:
        m = {k: v for k, v in self.sections["machine"].items() if k != "map"}
        return (f"{self.kind} seed {self.seed}: " + json.dumps(m) + " rated "
                + json.dumps({k: round(v, 6) if isinstance(v, float) else v
                              for k, v in self.rated.items()}))


def _rng(kind: str, seed: int, attempt: int) -> np.random.Generator:
    return np.random.default_rng([int(seed), KINDS.index(kind), attempt])


def _logu(g, lo, hi):
    return float(math.exp(g.uniform(math.log(lo), math.log(hi))))


def _controller(i_n, t_n, n_rpm, v_dc, lambda_m):
    i_max = i_n
    return {"i_max": i_max, "i_trip": 2.0 * i_max, "torque_max": t_n,
            "speed_max": n_rpm * RPM, "speed_trip": 1.25 * n_rpm * RPM,
            "v_dc_max": 1.3 * v_dc, "v_dc_min": 0.5 * v_dc, "current_bw": CURRENT_BW,
            "flux_min": 0.2 * lambda_m, "vsd_max": 0.335 * v_s(v_dc),
            "align_current": 0.5 * i_max}


def _sensors(i_trip, v_dc):
    return {"i_full_scale": 2.5 * i_trip, "v_full_scale": 2.0 * v_dc}


def _mtpa_linear(ld, lq, lam, i):
    """MTPA current angle of a linear PM machine at amplitude i: (i_d, i_q)."""
    if abs(lq - ld) < 1e-12 * lq:
        return 0.0, i
    dl = ld - lq
    i_d = (-lam - math.sqrt(lam * lam + 8.0 * dl * dl * i * i)) / (4.0 * dl) if dl < 0 else 0.0
    i_d = max(-i, min(0.0, i_d))
    return i_d, math.sqrt(max(i * i - i_d * i_d, 0.0))


def _rated_point(g, p, ld, lq, lam, rs, i_n, w_e, vs, n_rpm):
    """The rated point of a linear PM machine: the MTPA torque at i_n, the
    voltage it needs (refused beyond 0.95 v_s: the reason) and an inertia
    of 0.02 .. 0.5 t_n / w_m (a rated-torque start of 0.02 .. 0.5 s):
    (t_n, w_m, j)."""
    i_d, i_q = _mtpa_linear(ld, lq, lam, i_n)
    t_n = 1.5 * p * (lam * i_q + (ld - lq) * i_d * i_q)
    psi = math.hypot(lam + ld * i_d, lq * i_q)
    if w_e * psi + rs * i_n > 0.95 * vs:
        return "rated point beyond the voltage limit"
    w_m = n_rpm * RPM
    return t_n, w_m, g.uniform(0.02, 0.5) * t_n / w_m


def _linear(kind, g):
    v_dc = float(g.choice([24.0, 48.0, 310.0, 540.0]))
    vs = v_s(v_dc)
    p = int(g.integers(1, 25))
    n_rpm = _logu(g, 300.0, 6000.0)
    w_e = p * n_rpm * RPM
    if w_e / (2 * math.pi) > F_PWM / 20.0:
        return None, "rated electrical frequency above f_pwm / 20"
    i_n = _logu(g, 2.0, 40.0) if v_dc < 100 else _logu(g, 1.0, 15.0)
    lam = g.uniform(0.4, 0.75) * vs / w_e
    if kind == "spm":
        x = g.uniform(0.1, 0.5)
        lq = x * vs / (w_e * i_n)
        ld = lq
    else:
        x = g.uniform(0.3, 0.9)
        lq = x * vs / (w_e * i_n)
        ld = lq / g.uniform(1.5, 3.0)
    rs = g.uniform(0.005, 0.08) * vs / i_n
    rp = _rated_point(g, p, ld, lq, lam, rs, i_n, w_e, vs, n_rpm)
    if isinstance(rp, str):
        return None, rp
    t_n, w_m, j = rp
    mach = {"preset": "rubino2020_spm", "pole_pairs": p, "rs": rs, "ld": ld, "lq": lq,
            "lambda_m": lam}
    if kind == "spm":
        mach.pop("ld")
        mach.pop("lq")
        mach["ls"] = ld
    ctl = _controller(i_n, t_n, n_rpm, v_dc, lam)
    sections = {"machine": mach, "controller": ctl, "dc_link": {"voltage": v_dc},
                "mechanics": {"j": j, "b": 0.01 * t_n / w_m},
                "sensors": _sensors(ctl["i_trip"], v_dc), "board": {"preset": "g474_nucleo"}}
    rated = {"i_n": i_n, "t_n": t_n, "n_rpm": n_rpm, "v_dc": v_dc, "v_s": vs, "w_e": w_e,
             "tau_e": lq / rs, "e_pu": w_e * lam / vs, "x_pu": w_e * lq * i_n / vs,
             "saliency": lq / ld}
    return (sections, rated, None, ()), None


def _map(kind, g):
    from .fluxmap.presets import _scaled

    k = _logu(g, 0.05, 1.0)
    c = g.uniform(0.7, 2.5)
    r = g.uniform(2.0, 4.0)
    psi_n = REF_FLUX_PER_C * c
    pm = g.uniform(0.1, 0.3) * psi_n if kind == "pmsyr_map" else 0.0
    model = _scaled(k, c, r, psi_pm=pm)
    p = int(g.integers(1, 5))
    i_n = k * I_PER_K * g.uniform(0.7, 1.2)
    v_dc = float(g.choice([310.0, 540.0]))
    vs = v_s(v_dc)
    w_e = 0.8 * vs / psi_n
    n_rpm = w_e / (p * RPM)
    if w_e / (2 * math.pi) > F_PWM / 20.0:
        return None, "rated electrical frequency above f_pwm / 20"
    rs = g.uniform(0.01, 0.08) * vs / i_n
    half = 1.5 * i_n
    t_n = mtpa_torque_exact(model, p, i_n)
    w_m = n_rpm * RPM
    j = g.uniform(0.02, 0.5) * t_n / w_m
    ctl = _controller(i_n, t_n, n_rpm, v_dc, 0.0)
    ctl.pop("flux_min")
    ctl.pop("vsd_max")
    sections = {"machine": {"map": None, "pole_pairs": p, "rs": rs},
                "controller": ctl, "dc_link": {"voltage": v_dc},
                "mechanics": {"j": j, "b": 0.01 * t_n / w_m},
                "sensors": _sensors(ctl["i_trip"], v_dc), "board": {"preset": "g474_nucleo"}}
    rated = {"i_n": i_n, "t_n": t_n, "n_rpm": n_rpm, "v_dc": v_dc, "v_s": vs, "w_e": w_e,
             "k": k, "c": c, "r": r, "psi_pm": pm}
    return (sections, rated, model, (half, 41)), None


def _star(g):
    lm = _logu(g, 100e-6, 1000e-6)
    pa = g.uniform(0.1, 0.45) * (1 if g.uniform() < 0.5 else -1)
    ld, lq = lm * (1 + pa), lm * (1 - pa)
    m0 = g.uniform(0.0, 0.15) * (ld + lq)
    # the split of the 2theta terms between self (L2) and mutual (M2):
    # L2 + 2 M2 = L_d - L_q is fixed, L2 - M2 sets the DFC signal's amplitude
    # (docs/dfc.md; 0 carries no position): |L2 - M2| in [0.1, 0.3] L0
    l0 = 0.5 * (ld + lq) + m0
    sig = g.uniform(0.1, 0.3) * l0 * (1 if g.uniform() < 0.5 else -1)
    m2 = (ld - lq - sig) / 3.0
    rs = _logu(g, 0.1, 3.0)
    p = int(g.integers(2, 13))
    v_dc = 24.0
    vs = v_s(v_dc)
    n_rpm = _logu(g, 500.0, 3000.0)
    w_e = p * n_rpm * RPM
    if w_e / (2 * math.pi) > F_PWM / 20.0:
        return None, "rated electrical frequency above f_pwm / 20"
    lam = g.uniform(0.4, 0.75) * vs / w_e
    i_n = _logu(g, 1.0, 10.0)
    if rs * i_n > 0.3 * vs:
        return None, "R_s i_n above 0.3 v_s"
    rp = _rated_point(g, p, ld, lq, lam, rs, i_n, w_e, vs, n_rpm)
    if isinstance(rp, str):
        return None, rp
    t_n, w_m, j = rp
    noise = g.uniform(0.0, 0.06)
    mach = {"preset": "fabbri2022_t51", "pole_pairs": p, "rs": rs, "ld": ld, "lq": lq,
            "lambda_m": lam, "star_m0": m0, "star_m2": m2}
    ctl = _controller(i_n, t_n, n_rpm, v_dc, lam)
    sections = {"machine": mach, "controller": ctl, "dc_link": {"voltage": v_dc},
                "mechanics": {"j": j, "b": 0.01 * t_n / w_m},
                "sensors": {**_sensors(ctl["i_trip"], v_dc), "star_noise": noise},
                "board": {"preset": "g474_nucleo", "asym_edges": 1},
                "inverter": {"model": "switching", "dead_time": 5e-7}}
    rated = {"i_n": i_n, "t_n": t_n, "n_rpm": n_rpm, "v_dc": v_dc, "v_s": vs, "w_e": w_e,
             "star_p": (ld - lq) / (ld + lq), "star_noise": noise}
    return (sections, rated, None, ()), None


def mtpa_torque_exact(model, p: int, amp: float, n: int = 40001) -> float:
    """The largest torque at current amplitude amp of the analytic model
    (exact flux, no grid), by a dense sweep of the current angle over the
    whole circle: T = 3/2 p (psi_d i_q - psi_q i_d) (a frame rotation keeps
    it, so the SyR frame serves)."""
    th = np.linspace(-math.pi, math.pi, n)
    i_d, i_q = amp * np.cos(th), amp * np.sin(th)
    pd, pq = model.flux(i_d, i_q)
    return float((1.5 * p * (pd * i_q - pq * i_d)).max())


def draw(kind: str, seed: int) -> Drawn:
    """The machine of (kind, seed): redrawn (bounded, MAX_TRIES) until it meets
    the ranges' joint conditions; FluxdriveError if none does."""
    if kind not in KINDS:
        raise FluxdriveError(f"machines: unknown kind {kind!r}", hint=f"one of {', '.join(KINDS)}")
    why = ""
    for attempt in range(MAX_TRIES):
        g = _rng(kind, seed, attempt)
        if kind in ("spm", "ipm"):
            out, why = _linear(kind, g)
        elif kind == "star":
            out, why = _star(g)
        else:
            out, why = _map(kind, g)
        if out is not None:
            sections, rated, model, grid = out
            return Drawn(kind, int(seed), attempt + 1, sections, rated, model, grid)
    raise FluxdriveError(f"machines: no valid {kind} machine for seed {seed} in {MAX_TRIES} draws "
                         f"(last: {why})")


def write_map(d: Drawn, folder: Path, half: float | None = None, n: int | None = None) -> Path:
    """The drawn map machine's flux map (fluxdrive convention, real arrays)
    as an .npz in folder, on its grid (+-half A, n points per axis: by
    default the draw's, 1.5 times the rated current); the machine section's
    `map` set to it."""
    from .fluxmap.model import syr_to_fluxdrive

    half = half or d.grid[0]
    n = n or d.grid[1]
    a = np.linspace(-half, half, n)
    D, Q = np.meshgrid(a, a)
    pd, pq = d.model.flux(D, Q)
    i_d, i_q, psi_d, psi_q = syr_to_fluxdrive(a, a.copy(), pd, pq)
    folder.mkdir(parents=True, exist_ok=True)
    tag = "" if (half, n) == tuple(d.grid) else f"_{half:.4g}A"
    path = (folder / f"{d.kind}_{d.seed}{tag}.npz").resolve()
    np.savez(path, i_d=i_d, i_q=i_q, psi_d=psi_d, psi_q=psi_q,
             pole_pairs=np.int64(d.sections["machine"]["pole_pairs"]),
             convention=np.str_("fluxdrive"))
    d.sections["machine"]["map"] = str(path)
    return path


def main_draw(args) -> int:
    if not 1 <= args.count <= 1000:
        raise FluxdriveError(f"machines draw: --count must be in 1 .. 1000 (got {args.count})")
    out = []
    for s in range(args.seed, args.seed + args.count):
        d = draw(args.kind, s)
        if d.model is not None:
            write_map(d, Path(args.map_dir))
        out.append({"kind": d.kind, "seed": d.seed, "rated": d.rated, **d.sections})
    print(json.dumps(out if args.count > 1 else out[0], indent=2))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("machines", help="random machines within physical ranges "
                                        "(docs/machines.md)")
    ms = p.add_subparsers(dest="machines_cmd", required=True)
    q = ms.add_parser("draw", help="draw machines: their scenario sections as JSON")
    q.add_argument("--kind", required=True, choices=KINDS)
    q.add_argument("--seed", type=int, default=1)
    q.add_argument("--count", type=int, default=1)
    q.add_argument("--map-dir", default=".", help="where the map kinds' .npz files go")
    q.set_defaults(func=main_draw)
