#!/usr/bin/env python3
"""Run the Rubino 2020 acceptance tests on deliberately broken scenarios.

Each break is a set of overrides (dotted key = JSON value) applied to
temporary copies of sil/scenarios/rubino_*.json, never to the committed
files; the suite (tests/python/test_rubino2020.py) then runs on the copies
through FLUXDRIVE_RUBINO_SCENARIOS and the tests that fail are listed. A
break that no test catches is a hole in the acceptance tests.

    .venv/bin/python scripts/rubino-breaks.py              # the built-in breaks
    .venv/bin/python scripts/rubino-breaks.py --list
    .venv/bin/python scripts/rubino-breaks.py 'controller.v_margin=0.9' 'controller.delta_max=1.2'
        # one custom break made of these overrides

Keys under controller.estimates are applied only to scenarios without
estimates of their own (the nominal runs), so that the detuned runs keep
their paper detuning; a key "TEXT:KEY" only to the files whose name
contains TEXT. The runner: $FLUXDRIVE_SIL, else
build/host-release/sil/fluxdrive-sil.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
I_MAX = 2.5 * math.sqrt(2.0)
BW = 2 * math.pi * 1000.0

BREAKS: dict[str, dict[str, object]] = {
    "delta_max 65 deg": {"controller.delta_max": math.radians(65.0)},
    "delta_max 85 deg": {"controller.delta_max": math.radians(85.0)},
    "i_max +10 %": {"controller.i_max": 1.1 * I_MAX},
    "i_max -10 %": {"controller.i_max": 0.9 * I_MAX},
    "PI-DFVC bandwidths /4": {"controller.dfvc_flux_bw": BW / 4, "controller.dfvc_iqs_bw": BW / 4},
    "v_margin 0.8": {"controller.v_margin": 0.8},
    "v_margin 0.9": {"controller.v_margin": 0.9},
    "flux_obs_wc 12.5 rad/s (/10)": {"controller.flux_obs_wc": 12.5},
    "flux_obs_wc 1250 rad/s (x10)": {"controller.flux_obs_wc": 1250.0},
    "estimates: L_s x1.1": {"controller.estimates.ls_scale": 1.1},
    "estimates: lambda_m x0.9": {"controller.estimates.lambda_m_scale": 0.9},
    "estimates: R_s x1.5": {"controller.estimates.rs_scale": 1.5},
    "PI-DFVC bandwidths x1.25": {"controller.dfvc_flux_bw": 1.25 * BW, "controller.dfvc_iqs_bw": 1.25 * BW},
    "PI-DFVC scenarios run DB-DFVC": {"_pi:controller.law": "db_dfvc"},
    "accel_max x1.5 (1800 rpm/s)": {"controller.accel_max": 1.5 * 1200 * math.pi / 30},
    "plant DC link 280 V": {"dc_link.voltage": 280.0},
    # not a break: an ideal encoder removes the half-count static error, so
    # the strict xfail on settling must turn into a failure (XPASS)
    "(control) encoder 2^20 counts": {"sensors.encoder_cpr": 1 << 20},
}


def apply(scenario: dict, overrides: dict[str, object], stem: str) -> dict:
    has_estimates = "estimates" in scenario.get("controller", {})
    for key, value in overrides.items():
        if ":" in key:  # "bandwidth_pi:controller.law": only files whose name contains bandwidth_pi
            only, key = key.split(":", 1)
            if only not in stem:
                continue
        if key.startswith("controller.estimates.") and has_estimates:
            continue
        node = scenario
        *path, leaf = key.split(".")
        for part in path:
            node = node.setdefault(part, {})
        node[leaf] = value
    return scenario


def _test_of_line(lines: list[str], n: int) -> str:
    for k in range(n - 1, -1, -1):
        m = re.match(r"def (test_\w+)", lines[k])
        if m:
            return m.group(1)
    return "?"


def run_suite(scenario_dir: Path, sil: Path) -> tuple[list[str], list[str], str]:
    """(failed assertions: test, line, source, message; xfailed tests; pytest's last line)."""
    test_file = ROOT / "tests" / "python" / "test_rubino2020.py"
    env = dict(os.environ, FLUXDRIVE_RUBINO_SCENARIOS=str(scenario_dir), FLUXDRIVE_SIL=str(sil),
               COLUMNS="400",
               PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT / "tools" / "src"),
                                                        os.environ.get("PYTHONPATH")])))
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-rA", "--tb=line", "-p", "no:cacheprovider",
                          str(test_file)], cwd=ROOT, env=env, capture_output=True, text=True)
    src = test_file.read_text().splitlines()
    failed, xfailed = [], []
    for line in res.stdout.splitlines():
        m = re.match(r"^(/\S+test_rubino2020\.py):(\d+): (.*)$", line)
        if m:  # one per failure (--tb=line): the failing assertion
            n = int(m.group(2))
            failed.append(f"{_test_of_line(src, n)} line {n} `{src[n - 1].strip()}`: {m.group(3)[:160]}")
            continue
        m = re.match(r"^(FAILED|ERROR|XFAIL|XPASS) \S+::(\w+)(?: - (.*))?$", line)
        if not m:
            continue
        kind, name, msg = m.groups()
        if kind == "XFAIL":
            xfailed.append(name)
        elif not any(f.startswith(name + " ") for f in failed):
            failed.append(f"{name}: {(msg or 'failed with no assertion: a strict XPASS, the expected failure is gone')[:200]}")
    # --tb=line also prints the assertions of the expected failures
    failed = [f for f in failed if f.split(" ", 1)[0].rstrip(":") not in xfailed]
    tail = res.stdout.strip().splitlines()[-1] if res.stdout.strip() else res.stderr[-300:]
    return failed, xfailed, tail


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("override", nargs="*", help="KEY=JSON, e.g. controller.v_margin=0.9 (one custom break)")
    ap.add_argument("--list", action="store_true", help="list the built-in breaks")
    ap.add_argument("--only", metavar="TEXT", help="run the built-in breaks whose name contains TEXT")
    args = ap.parse_args()
    if args.list:
        for name, ov in BREAKS.items():
            print(f"{name}: {json.dumps(ov)}")
        return 0
    sil = Path(os.environ.get("FLUXDRIVE_SIL") or ROOT / "build" / "host-release" / "sil" / "fluxdrive-sil")
    if args.override:
        breaks = {" ".join(args.override): {k: json.loads(v) for k, v in
                                            (o.split("=", 1) for o in args.override)}}
    else:
        breaks = {k: v for k, v in BREAKS.items() if not args.only or args.only in k}
    sources = sorted((ROOT / "sil" / "scenarios").glob("rubino_*.json"))
    uncaught = []
    for name, overrides in breaks.items():
        with tempfile.TemporaryDirectory(prefix="rubino-break-") as tmp:
            for src in sources:
                sc = apply(json.loads(src.read_text()), overrides, src.stem)
                (Path(tmp) / src.name).write_text(json.dumps(sc, indent=1))
            failed, xfailed, tail = run_suite(Path(tmp), sil)
        print(f"== {name}  {json.dumps(overrides)}")
        print(f"   {tail}")
        for f in failed:
            print(f"   caught by {f}")
        if xfailed:
            print(f"   (xfail as expected: {', '.join(xfailed)})")
        if not failed:
            uncaught.append(name)
            print("   NOT CAUGHT")
    # exit 1 when a real break (not a "(control)" run) went through
    return 1 if any(not n.startswith("(control)") for n in uncaught) else 0


if __name__ == "__main__":
    sys.exit(main())
