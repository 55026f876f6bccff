"""Commissioning: rs and ldq in the SIL against the plant's truth (issue 25 a, b;
docs/commissioning.md).

Each case builds a scenario: a preset machine or a drawn one
(`fluxdrive.machines`, fixed seeds; more with FLUXDRIVE_SEEDS or --seed). It
adds current noise (`sensors.i_noise`) on the board's ADC quantisation, dead
time, a free rotor, and `"commission": [{"proc": "rs"}, {"proc": "ldq"}]`.
It runs the SIL and compares the procedure results in the summary's
"commission" entries with the truth from `--print-config` (the resolved
plant machine). The limits are the issue's:
  - R_s within 2 %; L_d and L_q within 5 % (linear machines);
  - the true peak current within the procedure's limit: rs's `id_rs_current`
    (0: i_max / 2); ldq's design bound of 1.5 i_b (i_b = i_max / 3);
  - the rotor's movement within the stated bound: rs one electrical turn
    plus a quarter for the swing, ldq half a turn plus a quarter;
  - with the average inverter, the voltage error at the top level within
    10 % of the dead time's plateau, (4/3) v_dc t_dead / ts along alpha.
At least one rs case runs the switching inverter.

Broken on purpose (tests/mutation/mutants.json): rs_single_level (R = V / I)
fails test_rs_* by the dead time's V_0 / I; ldq_delay fails test_ldq_*;
rs_swing_window (each level's window no longer between two of the swing's
turning points, proc_swing.c) fails test_rs_random_machines[spm-2]
(R_s -5.6 %).
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import tempfile

import pytest

from conftest import REAL_SIL
from fluxdrive import machines as mach

SEEDS_SPM = [1, 2, 3]
SEEDS_IPM = [1, 2]
LINEAR_PRESETS = ["rubino2020_spm", "fabbri2022_t51"]
TOL_R = 0.02
TOL_L = 0.05

real_sil = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")


def _seeds(config, base):
    extra = [int(s) for s in os.environ.get("FLUXDRIVE_SEEDS", "").split()]
    extra += list(config.getoption("--seed") or [])
    return extra or base


def _run(sc: dict):
    """Runs the SIL: (summary, resolved config), or skips when the runner has
    no commission path yet."""
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "sc.json")
        out = os.path.join(d, "summary.json")
        with open(p, "w") as f:
            json.dump(sc, f)
        cfg = subprocess.run([str(REAL_SIL), p, "--print-config"], capture_output=True, text=True,
                             timeout=60)
        if cfg.returncode != 0 and "commission" in cfg.stderr:
            pytest.skip("the SIL has no commission path: " + cfg.stderr.strip()[:200])
        assert cfg.returncode == 0, cfg.stderr
        r = subprocess.run([str(REAL_SIL), p, "--summary", out], capture_output=True, text=True,
                           timeout=600)
        assert r.returncode == 0, r.stderr
        with open(out) as f:
            return json.load(f), json.loads(cfg.stdout)


def _scenario(sections: dict, name: str, inverter: str = "average") -> dict:
    s = json.loads(json.dumps(sections))
    s.setdefault("controller", {})
    s["controller"].update({"law": "foc", "mode": "torque"})
    s["mechanics"] = dict(s.get("mechanics", {}), mode="free")
    s["inverter"] = {"model": inverter, "dead_time": 1e-6}
    i_max = s["controller"].get("i_max")
    s.setdefault("sensors", {})
    s["sensors"]["i_noise"] = 0.002 * (i_max or 3.5)
    # rs waits for the swing's turning points and for it to calm: up to
    # 7 s on the seeds
    s.update({"name": name, "duration": 9.0,
              "references": {"torque": [{"type": "const", "value": 0.0}]},
              "commission": [{"proc": "rs"}, {"proc": "ldq"}]})
    return s


def _entry(summary: dict, proc: str) -> dict:
    for e in summary["commission"]:
        if e["proc"] == proc:
            return e
    raise AssertionError(f"no {proc} in the summary's commission")


def _check_rs(summary, cfg, name):
    m = cfg["machine"]
    c = cfg["controller"]
    e = _entry(summary, "rs")
    r = e["result"]
    print(f"{name}: rs {e['status']} R {r[0]:.6g} (true {m['rs']:.6g}) v_err {r[1]:.4g} V "
          f"knee {r[2]:.4g} A i_peak {e['i_peak']:.4g} move {e['move']:.4g}")
    assert e["status"] == "done", e
    assert abs(r[0] / m["rs"] - 1.0) < TOL_R
    lim = min(c.get("id_rs_current") or 0.5 * c["i_max"], c["i_max"])
    assert e["i_peak"] <= lim * 1.02  # the PWM ripple of the switching inverter
    assert e["move"] <= 1.25 * 2.0 * math.pi / m["pole_pairs"]
    return e


def _check_ldq(summary, cfg, name, saturated=False):
    m = cfg["machine"]
    c = cfg["controller"]
    e = _entry(summary, "ldq")
    r = e["result"]
    print(f"{name}: ldq {e['status']} L_d {r[0]:.6g} (true {m.get('ld')}) L_q {r[1]:.6g} "
          f"(true {m.get('lq')}) i_b {r[2]:.4g} i_peak {e['i_peak']:.4g} move {e['move']:.4g}")
    assert e["status"] == "done", e
    i_b = min(c.get("id_ldq_current") or c["i_max"] / 3.0, 0.5 * c["i_max"])
    assert e["i_peak"] <= 1.5 * i_b * 1.02
    assert e["move"] <= 2.0 * math.pi / m["pole_pairs"]
    if not saturated:
        assert abs(r[0] / m["ld"] - 1.0) < TOL_L
        assert abs(r[1] / m["lq"] - 1.0) < TOL_L
    else:  # the incremental inductances at the bias: positive, finite
        assert 0.0 < r[0] < 10.0 and 0.0 < r[1] < 10.0


# Known open for ldq (docs/commissioning.md, "ldq"): rs meets its bounds on
# these, ldq not yet. ipm seed 1: ldq's true peak current 2.43 A over its
# design bound 1.5 i_b = 1.98 A (during the d injection's amplitude trials),
# L_d and L_q within 0.5 %. (spm seed 3 failed `control` until ldq's
# alignment damped the swing, as rs does.)
LDQ_OPEN = {("ipm", 1): "ipm seed 1: ldq's true peak current 2.43 A over its design bound "
                        "1.5 i_b = 1.98 A in the d injection's trials (open, docs/commissioning.md)"}


@real_sil
@pytest.mark.parametrize("preset", LINEAR_PRESETS)
def test_rs_ldq_presets(preset):
    sc = _scenario({"machine": {"preset": preset}, "board": {"preset": "g474_nucleo"}},
                   f"commission rl {preset}")
    summary, cfg = _run(sc)
    e = _check_rs(summary, cfg, preset)
    # the average inverter's dead-time plateau along alpha: 2/3 (e + e/2 * 2)
    v0 = cfg["v_dc"] * cfg["dead_time"] / cfg["ts"]
    assert abs(e["result"][1] / (4.0 / 3.0 * v0) - 1.0) < 0.10
    _check_ldq(summary, cfg, preset)


@real_sil
def test_rs_switching_inverter():
    sc = _scenario({"machine": {"preset": "rubino2020_spm"}, "board": {"preset": "g474_nucleo"}},
                   "commission rl switching", inverter="switching")
    sc["commission"] = [{"proc": "rs"}]
    sc["duration"] = 5.0
    summary, cfg = _run(sc)
    _check_rs(summary, cfg, "rubino2020_spm switching")


def pytest_generate_tests(metafunc):
    """The random machines' cases: spm and ipm seeds (FLUXDRIVE_SEEDS or --seed
    replace them); rs is checked on all, ldq's known open ones are an xfail
    (LDQ_OPEN)."""
    if "machine_case" in metafunc.fixturenames:
        cases = [("spm", s) for s in _seeds(metafunc.config, SEEDS_SPM)]
        cases += [("ipm", s) for s in _seeds(metafunc.config, SEEDS_IPM)]
        metafunc.parametrize("machine_case", [pytest.param(c, id=f"{c[0]}-{c[1]}")
                                              for c in cases])


_DRAWN: dict = {}


def _drawn_run(machine_case):
    """The drawn machine's rs and ldq run, once for both tests."""
    if machine_case not in _DRAWN:
        kind, seed = machine_case
        d = mach.draw(kind, seed)
        print(d.params_line())
        _DRAWN[machine_case] = _run(_scenario(d.sections, f"commission rl {kind} {seed}"))
    return _DRAWN[machine_case]


@real_sil
def test_rs_random_machines(machine_case):
    summary, cfg = _drawn_run(machine_case)
    _check_rs(summary, cfg, "{} {}".format(*machine_case))


@real_sil
def test_ldq_random_machines(machine_case):
    summary, cfg = _drawn_run(machine_case)
    name = "{} {}".format(*machine_case)
    if machine_case not in LDQ_OPEN:
        _check_ldq(summary, cfg, name)
        return
    try:  # a known open case of ldq: an xfail, and an error once it passes (strict)
        _check_ldq(summary, cfg, name)
    except AssertionError:
        pytest.xfail(LDQ_OPEN[machine_case])
    pytest.fail("XPASS(strict): " + LDQ_OPEN[machine_case])


# The reluctance presets (flux maps): a reluctance or PM-assisted rotor
# swings asymmetrically about the current and, started on its
# low-inductance axis, leaves it (docs/commissioning.md, rs): the bench of
# `fluxdrive commission --sil-preset` (fluxdrive.commission_sil: device
# drops, dead time, noise). R_s within 2 % of the plant's, the current
# within the limit, the movement within its bound.
RELUCTANCE_PRESETS = ["syr_1k1", "pmasyr_file"]


@real_sil
@pytest.mark.parametrize("preset", RELUCTANCE_PRESETS)
def test_rs_reluctance_presets(preset):
    from fluxdrive import commission_sil as cs
    sc = cs.scenario(preset, "rs")
    sc["duration"] = 9.0
    summary, cfg = _run(sc)
    _check_rs(summary, cfg, preset)


@real_sil
def test_rs_with_noisy_current_sensors():
    """Drawn ipm seed 2 (R_s 0.052 Ohm, i_max 40 A) with current noise of
    0.6 % of i_max per phase, three times the other cases': rs done, R_s
    within 2 %. The current-sum check's floor is the noise the offsets
    measured (3 sigma) plus the ADC's rounding (proc_offset.c, drive.c):
    with the rounding alone, the noise of the sum at the low levels trips
    `current_sensor` (the procedure aborted)."""
    d = mach.draw("ipm", 2)
    sc = _scenario(d.sections, "commission rl noisy sensors")
    sc["commission"] = [{"proc": "rs"}]
    sc["sensors"]["i_noise"] = 0.006 * sc["controller"].get("i_max", 3.5)
    summary, cfg = _run(sc)
    _check_rs(summary, cfg, "ipm 2, noisy sensors")
