#!/usr/bin/env python3
"""rs and ldq on the presets and drawn machines: the table of
docs/commissioning.md ("The free rotor's swing").

    FLUXDRIVE_SIL=build/host-release/sil/fluxdrive-sil \\
        .venv/bin/python scripts/commission_rl_table.py [--seeds 1 2 ...]

Each machine runs the scenario of tests/python/test_commission_rl.py (rs
then ldq through the SIL's commission path: average inverter, 1 us dead
time, current noise, a free rotor) and one Markdown row is printed: R_s,
L_d and L_q against the plant's truth, the rotor's largest movement [rad
mechanical] in each procedure, and rs's SIL time.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools" / "src"))
sys.path.insert(0, str(ROOT / "tests" / "python"))

from fluxdrive import machines as mach  # noqa: E402
import test_commission_rl as T  # noqa: E402


def pct(a: float, b: float) -> str:
    return f"{(a / b - 1) * 100:+.2f} %"


def row(name: str, sc: dict) -> str:
    summ, cfg = T._run(sc)
    m = cfg["machine"]
    c = {e["proc"]: e for e in summ["commission"]}
    rs, lq = c["rs"], c.get("ldq")
    rsr = pct(rs["result"][0], m["rs"]) if rs["status"] == "done" else \
        f"{rs['status']} ({','.join(rs['fault'])})"
    if lq and lq["status"] == "done":
        ldq = f"{pct(lq['result'][0], m['ld'])} / {pct(lq['result'][1], m['lq'])}"
    else:
        ldq = f"{lq['status']} ({','.join(lq['fault'])})" if lq else "-"
    return (f"| {name} | {rsr} | {rs['move']:.3f} | {rs['t1'] - rs['t0']:.2f} | {ldq} | "
            f"{lq['move'] if lq else 0.0:.3f} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(1, 9)))
    a = ap.parse_args()
    print("| machine | R_s | rs move | rs time [s] | L_d / L_q | ldq move |")
    print("|---|---|---|---|---|---|")
    for p in T.LINEAR_PRESETS:
        print(row(p, T._scenario({"machine": {"preset": p}, "board": {"preset": "g474_nucleo"}}, p)),
              flush=True)
    for kind in ("spm", "ipm"):
        for s in a.seeds:
            d = mach.draw(kind, s)
            print(row(f"{kind} {s}", T._scenario(d.sections, f"{kind} {s}")), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
