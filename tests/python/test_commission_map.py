"""Issue 25 procedure c: the flux maps at standstill (firmware/app/proc_fmap.c)
run in the SIL on the flux-map presets, rotor free, average inverter with
its 1 us dead time and device drops (switch 0.8 V + 50 mOhm, diode 1.0 V +
30 mOhm), current and voltage noise, a 4096-count encoder; the
points assembled on the host (fluxdrive.commission_map) and compared with
the plant's map. Limits from the issue: the maps within 3 % rms and 6 %
worst over the identified range (|psi - psi_true| over the largest
|psi_true| there), the MTPA from the identified map within 1 % of the true
map's torque per ampere at every current up to i_max; the current never
above the procedure's range (its trip margin, 1.25 I + 5 % i_max); the
rotor's movement within the bound docs/commissioning.md states (0.1 rad
mech on these machines' inertia). The PM flux at zero current is procedure
f's (standstill cannot see it): the plant's, added on the host.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

from conftest import REAL_SIL

from fluxdrive import commission_map as cm

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")

# preset: (i_max [A], dwell [s], grid nd x nq, movement bound [rad mech])
CASES = {
    "syr_1k1": (4.879, 0.012, 9, 5, 0.1),
    "pmasyr_file": (8.0, 0.006, 9, 5, 0.1),
}


def _assert_map_limits(e: dict) -> None:
    """The issue's limits on an identified map (commission_map.errors):
    3 % rms and 6 % worst against the plant's, at the points and over the
    map; the MTPA's torque per ampere within 1 % of the true map's."""
    assert 0.0 <= e["map_rms"] <= 0.03 and 0.0 <= e["map_worst"] <= 0.06
    assert 0.0 <= e["points_rms"] <= 0.03 and 0.0 <= e["points_worst"] <= 0.06
    assert -1e-6 <= e["mtpa_loss_worst"] <= 0.01


def scenario(preset: str) -> dict:
    i_max, dwell, nd, nq, _ = CASES[preset]
    return {
        "name": f"fmap on {preset}",
        "duration": 6.0,
        "machine": {"preset": preset},
        "inverter": {"model": "average", "dead_time": 1e-6, "v_th_sw": 0.8, "r_on_sw": 0.05,
                     "v_f_diode": 1.0, "r_diode": 0.03},
        "mechanics": {"mode": "free"},
        "sensors": {"v_full_scale": 1000, "i_noise": 0.002, "v_noise": 0.1, "encoder_cpr": 4096},
        "controller": {"law": "foc", "mode": "torque", "i_max": i_max, "i_trip": 1.5 * i_max,
                       "id_fmap_current": i_max, "id_fmap_nd": nd, "id_fmap_nq": nq,
                       "id_fmap_dwell": dwell, "v_dc_max": 800, "v_dc_min": 200},
        "commission": [{"proc": "fmap"}],
    }


@pytest.mark.parametrize("preset", sorted(CASES))
def test_flux_maps_at_standstill(preset: str, tmp_path: Path) -> None:
    sc = scenario(preset)
    p = tmp_path / "sc.json"
    p.write_text(json.dumps(sc))
    out = tmp_path / "sum.json"
    r = subprocess.run([str(REAL_SIL), str(p), "--summary", str(out)], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    rec = next(c for c in json.loads(out.read_text())["commission"] if c["proc"] == "fmap")
    assert rec["status"] == "done", rec
    i_max, _, nd, nq, move = CASES[preset]
    truth = cm.truth_of(sc, tmp_path)
    pts = cm.points_of(rec, truth.pm_flux())
    # every grid point within the circle, once
    want = sum(1 for k in range(nq) for j in range(nd)
               if (2 * j / (nd - 1) - 1) ** 2 + (k / (nq - 1)) ** 2 <= 1 + 1e-6)
    assert len(pts) == want
    ident, measured = cm.assemble(pts, nd, nq, truth.pole_pairs)
    e = cm.errors(ident, measured, pts, truth, i_max)
    print(f"{preset}: points rms {100 * e['points_rms']:.2f} % worst "
          f"{100 * e['points_worst']:.2f} %, map rms {100 * e['map_rms']:.2f} % worst "
          f"{100 * e['map_worst']:.2f} %, MTPA loss {100 * e['mtpa_loss_worst']:.3f} %, "
          f"i_peak {rec['i_peak']:.3f} A, move {rec['move']:.4f} rad")
    _assert_map_limits(e)
    # the current within the procedure's bound, and it did drive the range
    assert 0.9 * i_max <= rec["i_peak"] <= 1.25 * i_max + 0.05 * i_max
    assert 0.0 <= rec["move"] <= move
    # the blob the tools and the firmware read
    b = tmp_path / "ident.fdmap"
    from fluxdrive.fluxmap import blob
    b.write_bytes(blob.to_bytes(ident))
    assert blob.read(b)["nd"] == nd


# Random saturated machines of the unseen-machines generator
# (`fluxdrive machines draw --kind syr_map|pmsyr_map`: the analytic model
# scaled in current, flux and saliency, 1-4 pole pairs, 310 / 540 V, R_s 1-8 %
# of the rated voltage): seeds in CI, more with FLUXDRIVE_FMAP_SEEDS="syr_map:4
# pmsyr_map:5". The grid is the presets' (9 x 5, 12 ms dwell); the drive's
# lambda_m is the plant's PM flux (procedure f's result, given as a
# parameter file: standstill cannot see it). The rotor's movement is
# printed and bounded only by the procedure's own trips: on the light rotors
# the generator draws (J 0.02 .. 0.5 of the rated torque over the rated
# speed) the rocking reaches 1.5 rad electrical (docs/commissioning.md).
DRAWN = ["syr_map:1", "syr_map:2", "pmsyr_map:1", "pmsyr_map:2", "pmsyr_map:3"]
DRAWN += os.environ.get("FLUXDRIVE_FMAP_SEEDS", "").split()


@pytest.mark.parametrize("case", DRAWN)
def test_flux_maps_of_drawn_machines(case: str, tmp_path: Path) -> None:
    from fluxdrive import machines as mach

    kind, seed = case.split(":")
    d = mach.draw(kind, int(seed))
    mach.write_map(d, tmp_path)
    ctl = dict(d.sections["controller"])
    i_max = ctl["i_max"]
    nd, nq = 9, 5
    sc = {"name": f"fmap on {case}", "duration": 6.0,
          "machine": d.sections["machine"], "dc_link": d.sections["dc_link"],
          "board": d.sections["board"],
          "inverter": {"model": "average", "dead_time": 1e-6, "v_th_sw": 0.8, "r_on_sw": 0.05,
                       "v_f_diode": 1.0, "r_diode": 0.03},
          "mechanics": {"mode": "free", **{k: d.sections["mechanics"][k] for k in ("j", "b")}},
          "sensors": {**d.sections["sensors"], "i_noise": 4e-4 * i_max, "encoder_cpr": 4096},
          "controller": {**ctl, "law": "foc", "mode": "torque", "id_fmap_current": i_max,
                         "id_fmap_nd": nd, "id_fmap_nq": nq, "id_fmap_dwell": 0.012},
          "commission": [{"proc": "fmap"}]}
    p = tmp_path / "sc.json"
    p.write_text(json.dumps(sc))
    params = tmp_path / "params.json"
    params.write_text(json.dumps({"lambda_m": d.rated["psi_pm"]}))
    out = tmp_path / "sum.json"
    r = subprocess.run([str(REAL_SIL), str(p), "--params", str(params), "--summary", str(out)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    rec = next(c for c in json.loads(out.read_text())["commission"] if c["proc"] == "fmap")
    assert rec["status"] == "done", rec
    truth = cm.truth_of(sc, tmp_path)
    pts = cm.points_of(rec)
    ident, measured = cm.assemble(pts, nd, nq, truth.pole_pairs)
    e = cm.errors(ident, measured, pts, truth, i_max)
    pp = d.sections["machine"]["pole_pairs"]
    print(f"{case}: map rms {100 * e['map_rms']:.2f} % worst {100 * e['map_worst']:.2f} %, "
          f"MTPA loss {100 * e['mtpa_loss_worst']:.3f} %, i_peak {rec['i_peak'] / i_max:.3f} i_max, "
          f"move {rec['move'] * pp:.3f} rad el")
    _assert_map_limits(e)
    assert 0.9 * i_max <= rec["i_peak"] <= 1.25 * i_max + 0.05 * i_max
