"""The encoder identifications (issue 25 d-g; docs/commissioning.md, "poles,
enc, flux, mech") in the SIL: a scenario's `commission` key runs poles,
enc, flux and mech in turn with the drive disabled, on the default preset
(rubino2020_spm, 4096 counts) and on random machines of the generator
(tools/src/fluxdrive/machines.py, spm and ipm, fixed seeds), with current
noise, dead time (average inverter), Coulomb friction (a passive load of 1 %
of the rated torque) and the machine's viscous friction. Each result
against the plant's truth with the issue's limits: pole pairs exact,
encoder offset within 1 deg electrical, lambda_m within 2 %, J within 5 %,
friction (Coulomb and viscous) within 10 % (mech's constant-speed plateaus;
broken on purpose by hand: T_c, B left from the torque steps' fit, as on
main, fail test_friction[preset] by T_c -17 %); the true peak current within
each procedure's bound (1.3 id_i_test + 5 % i_max, proc_poles.c). The
encoder's offset: the plant's encoder reads the rotor's d axis at zero, so
the main run's truth is 0; a second run adds `inject.encoder_error` (a
misaligned encoder, e rad mech: truth p e electrical) for enc alone.
The controller's parameters are the plant's (the host writes each result
before the next procedure: pole_pairs, enc_offset, lambda_m), L_d, L_q the
ldq procedure's (here the truth).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import tempfile

import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import machines as mach

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")

I_TEST = 0.3  # x i_max: id_i_test's default
PROCS = ["poles", "enc", "flux", "mech"]
SEEDS = [1, 2, 3, 4, 5]


def _run(sc: dict) -> dict:
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "sc.json")
        with open(p, "w") as f:
            json.dump(sc, f)
        r = subprocess.run([str(REAL_SIL), p, "--summary", p + ".sum"], capture_output=True,
                           text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        with open(p + ".sum") as f:
            return json.load(f)


def _truth(sc: dict) -> dict:
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "sc.json")
        with open(p, "w") as f:
            json.dump(sc, f)
        r = subprocess.run([str(REAL_SIL), p, "--print-config"], capture_output=True, text=True,
                           timeout=60)
        assert r.returncode == 0, r.stderr
        return json.loads(r.stdout)


def _preset() -> tuple[dict, float, float]:
    with open(REPO_ROOT / "sil/scenarios/default.json") as f:
        sc = json.load(f)
    for k in ("references", "log"):
        sc.pop(k, None)
    sc["mechanics"] = {"mode": "free", "b": 0.002}
    sc["controller"] = {"law": "foc", "mode": "current"}
    return sc, 4.0, 0.0  # rated torque (Rubino: about 4 N m), rated speed unknown


def _drawn(kind: str, seed: int) -> tuple[dict, float]:
    d = mach.draw(kind, seed)
    sc = {k: dict(v) for k, v in d.sections.items()}
    sc["name"] = f"commission mech {kind} {seed}"
    sc["mechanics"] = {"mode": "free", **d.sections["mechanics"]}
    sc["sensors"] = {**d.sections["sensors"], "i_noise": 0.002 * d.rated["i_n"],
                     "encoder_cpr": 4096}
    sc["inverter"] = {"model": "average", "dead_time": 1e-6}
    sc["controller"] = {**d.sections["controller"], "law": "foc", "mode": "current"}
    return sc, d.rated["t_n"]


def _commission(sc: dict, t_n: float) -> tuple[dict, dict]:
    sc = json.loads(json.dumps(sc))
    sc["duration"] = 40.0
    sc.setdefault("inverter", {"model": "average", "dead_time": 1e-6})
    tc = 0.01 * t_n
    sc.setdefault("inject", {})["passive_load"] = {"coulomb": tc}
    sc["commission"] = [{"proc": p} for p in PROCS]
    out = _run(sc)
    truth = _truth(sc)
    return out, {**truth["machine"], "coulomb": tc,
                 "b": sc["mechanics"].get("b", 0.0), "i_max": truth["controller"]["i_max"]}


def _check(out: dict, tr: dict, friction: bool = False) -> list[str]:
    """The failures (empty: within every limit); friction: T_c and B alone."""
    c = {x["proc"]: x for x in out["commission"]}
    bad = []
    for p in PROCS:
        if p not in c:
            bad.append(f"{p}: not run (a procedure before it failed)")
            continue
        if c[p]["status"] != "done":
            bad.append(f"{p}: {c[p]['status']} {c[p]['fault']}")
        bound = 1.3 * I_TEST * tr["i_max"] + 0.05 * tr["i_max"]
        if not c[p]["i_peak"] <= bound:
            bad.append(f"{p}: i_peak {c[p]['i_peak']:.3f} > {bound:.3f}")
    if bad:
        return bad
    r = {p: c[p]["result"] for p in PROCS}
    if friction:
        if not abs(r["mech"][1] / tr["coulomb"] - 1) < 0.10:
            bad.append(f"T_c {r['mech'][1]:.6g} true {tr['coulomb']:.6g}")
        if tr["b"] > 0 and not abs(r["mech"][2] / tr["b"] - 1) < 0.10:
            bad.append(f"B {r['mech'][2]:.6g} true {tr['b']:.6g}")
        return bad
    if r["poles"][0] != tr["pole_pairs"] or r["poles"][1] != 1.0:
        bad.append(f"poles {r['poles'][:2]} true {tr['pole_pairs']}")
    e = math.degrees(math.remainder(r["enc"][0], 2 * math.pi))
    if not abs(e) < 1.0:
        bad.append(f"enc offset {e:.3f} deg")
    if not abs(r["flux"][0] / tr["lambda_m"] - 1) < 0.02:
        bad.append(f"lambda_m {r['flux'][0]:.5f} true {tr['lambda_m']:.5f}")
    if not abs(r["mech"][0] / tr["j"] - 1) < 0.05:
        bad.append(f"J {r['mech'][0]:.6g} true {tr['j']:.6g}")
    return bad


_RUNS: dict = {}


def _case(name: str) -> tuple[dict, dict]:
    """The commissioning of a case ("preset", or "spm:1" ...), run once."""
    if name not in _RUNS:
        if name == "preset":
            sc, t_n, _ = _preset()
        else:
            kind, seed = name.split(":")
            sc, t_n = _drawn(kind, int(seed))
        _RUNS[name] = _commission(sc, t_n)
    return _RUNS[name]


# Known failures. spm:4 (23 pole pairs, lambda_m 0.021 Vs): the encoder's
# offset -1.07 deg electrical and lambda_m +2.7 %. ipm:4's lambda_m (3.8
# mVs) is 2.4 % off (L_d |i| / lambda_m = 0.34: the inductances' error).
# (spm:4, ipm:2 and ipm:5 were stopped by the current_sensor protection
# until the offset procedure measured the sensors' noise as that check's
# floor, proc_offset.c; ipm:2 and ipm:5 now pass.)
_XFAIL = {
    "spm:4": "enc offset -1.07 deg electrical, lambda_m +2.7 % (23 pole pairs, 0.021 Vs)",
    "ipm:4": "lambda_m 2.4 % off on a 3.8 mVs machine (L_d |i| / lambda_m 0.34)",
}
CASES = ["preset"] + [f"{k}:{s}" for k in ("spm", "ipm") for s in SEEDS]


def _params(cases):
    return [pytest.param(c, marks=pytest.mark.xfail(reason=_XFAIL[c], strict=True))
            if c in _XFAIL else c for c in cases]


@pytest.mark.parametrize("case", _params(CASES))
def test_poles_enc_flux_inertia(case):
    out, tr = _case(case)
    assert _check(out, tr) == []


# The friction from constant-speed plateaus (proc_mech.c): spm:1's viscous B
# is +25 % (T_c -3.3 %): a 0.2 kg m^2 rotor whose B w at the top plateau is
# small against T_c; open (docs/commissioning.md, mech).
_XFAIL_FRICTION = {"spm:1": "spm:1: B +25 % from the plateaus (T_c -3.3 %): open (issue 25 g)"}


@pytest.mark.parametrize("case", [
    pytest.param(c, marks=pytest.mark.xfail(reason=_XFAIL_FRICTION[c], strict=True))
    if c in _XFAIL_FRICTION else c for c in CASES if c not in _XFAIL])
def test_friction(case):
    out, tr = _case(case)
    assert _check(out, tr, friction=True) == []


@pytest.mark.parametrize("err", [0.01, -0.05])
def test_encoder_offset(err):
    """A misaligned encoder (inject.encoder_error, rad mech): the offset p err."""
    sc, t_n, _ = _preset()
    sc = json.loads(json.dumps(sc))
    sc["duration"] = 12.0
    sc["inject"] = {"encoder_error": err, "passive_load": {"coulomb": 0.01 * t_n}}
    sc["commission"] = [{"proc": "enc"}]
    out = _run(sc)
    c = out["commission"][0]
    assert c["status"] == "done"
    true = math.remainder(21 * err, 2 * math.pi)
    e = math.degrees(math.remainder(c["result"][0] - true, 2 * math.pi))
    assert abs(e) < 1.0


def test_encoder_offset_on_a_flux_map_machine():
    """ipm_sat (a flux map: the parameter set's lambda_m is 0, the map's is
    0.08 Vs at zero current) on the commissioning bench of fluxdrive
    commission --sil-preset, a misaligned encoder: the offset within 1 deg
    electrical. The alignment's damping and settling take the machine's
    lambda_m; with the parameter set's 0 the rotor swung undamped and the
    offset came out 23 deg off (issue 25 e)."""
    from fluxdrive import commission_sil as cs
    err = 0.02  # rad mechanical
    sc = cs.scenario("ipm_sat", "enc")
    sc["duration"] = 9.0
    sc.setdefault("inject", {})["encoder_error"] = err
    out = _run(sc)
    c = out["commission"][0]
    assert c["status"] == "done", c
    true = math.remainder(4 * err, 2 * math.pi)
    e = math.degrees(math.remainder(c["result"][0] - true, 2 * math.pi))
    print(f"ipm_sat: enc offset {c['result'][0]:.5f} rad, true {true:.5f}: {e:+.3f} deg")
    assert abs(e) < 1.0
