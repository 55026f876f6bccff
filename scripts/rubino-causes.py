#!/usr/bin/env python3
"""The causes behind the residuals on docs/results-rubino2020.md, tested by
switching each suspected cause off in the flux-weakening ramp (Fig. 14).

Runs temporary copies of sil/scenarios/rubino_fw_ramp.json (never the
committed file) and prints, for each variant, the figures the results page
explains: the largest true current at every sample against the paper's
i_max, the largest load angle, the power held over 1000-1200 rpm against
the capability, and the lowest torque / capability ratio.

    .venv/bin/python scripts/rubino-causes.py

The runner: $FLUXDRIVE_SIL, else build/host-release/sil/fluxdrive-sil.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools" / "src"))

from fluxdrive import rubino2020 as rb  # noqa: E402

IDEAL_SENSORS = {"i_noise": 0.0, "v_noise": 0.0, "encoder_cpr": 1 << 20}

#: name -> (sensors overrides, inverter overrides, controller overrides)
VARIANTS: list[tuple[str, dict, dict, dict]] = [
    ("as committed (v_margin 0.99)", {}, {}, {}),
    ("v_margin 0.95", {}, {}, {"v_margin": 0.95}),
    ("v_margin 1.0 (the paper's v_s,max)", {}, {}, {"v_margin": 1.0}),
    ("no sensor noise", {"i_noise": 0.0, "v_noise": 0.0}, {}, {}),
    ("no noise, 2^20-count encoder", IDEAL_SENSORS, {}, {}),
    ("ideal sensors, no dead time", IDEAL_SENSORS, {"dead_time": 0.0}, {}),
    ("ideal sensors, average inverter, no dead time", IDEAL_SENSORS,
     {"model": "average", "dead_time": 0.0}, {}),
]


def main() -> int:
    sil = Path(os.environ.get("FLUXDRIVE_SIL") or ROOT / "build/host-release/sil/fluxdrive-sil")
    if not sil.is_file():
        print(f"fluxdrive-sil not built ({sil}): run ./scripts/demo.sh first", file=sys.stderr)
        return 2
    base = json.loads((ROOT / "sil" / "scenarios" / rb.SCENARIOS["fw"]).read_text())
    p = rb.PAPER
    print(f"paper limits: i_max {p.i_max:.4f} A, delta_max 80 deg; capability under them")
    print(f"{'variant':48s} {'i max [A]':>10s} {'over i_max':>10s} {'delta max':>10s} "
          f"{'power [W]':>10s} {'cap. [W]':>9s} {'T/cap min':>16s}")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        for name, sens, inv, ctl in VARIANTS:
            sc = json.loads(json.dumps(base))
            sc["sensors"].update(sens)
            sc["inverter"].update(inv)
            sc["controller"].update(ctl)
            path = out / "fw.json"
            path.write_text(json.dumps(sc))
            fw = rb.ramp_metrics(rb.run(sil, path, out))
            print(f"{name:48s} {fw.current_max:10.4f} {100 * (fw.current_max / p.i_max - 1):+9.2f}% "
                  f"{fw.delta_max_deg:9.2f}d {fw.power_top:10.0f} {fw.power_top_model:9.0f} "
                  f"{100 * fw.worst_ratio:6.1f}% @{fw.worst_ratio_rpm:5.0f} rpm"
                  + (f"  faults: {fw.faults}" if fw.faults else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
