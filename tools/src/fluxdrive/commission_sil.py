"""Commissioning a preset in the SIL, offline (issue 25: "closed loop on the
identified values", "duration of a full commissioning per preset").

``fluxdrive commission --sil-preset NAME --out F`` runs the preset's
identification procedures one after the other, each as its own SIL run with
the scenario's ``commission`` key (``sil/runner/sil_commission.c``; the
drive disabled: the offsets, then the procedure, then the gates off), the
parameters found so far applied over the drive (``--params``), as
``fluxdrive commission`` over CAN writes each result into the drive before
the next procedure. The results go through the same
:data:`fluxdrive.commission.RESULTS` and :func:`fluxdrive.commission.parameter_file`,
so the file is the one the CAN command writes; a ``fmap`` run adds the
drive's own map file (the points assembled by
:mod:`fluxdrive.commission_map`, its MTPA / MTPV tables) as ``"map"``.

The plant is the preset's machine on a bench with the errors a bench has:
current noise, the board's ADC quantisation, 1 us dead time, device drops
(``BENCH_INVERTER``, ``MOSFET_INVERTER``), a free rotor with its friction. The drive starts from the
preset's parameter set: the identified values replace the preset's, the
rest (limits, gains, i_max) stays.

Then::

    FLUXDRIVE_PARAMS=F pytest tests/python/test_rubino2020.py ...

runs a paper's acceptance tests with the commissioned parameters in place
of the preset's (``fluxdrive commission --sil-preset NAME --accept``: the
tests :data:`ACCEPTANCE` lists for the machine). ``--durations`` prints
each procedure's SIL time (t1 - t0) and the total, per preset.
"""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fluxdrive import params
from fluxdrive.commission import parameter_file, report, results_of, truth_from_sil
from fluxdrive.errors import FluxdriveError

REPO = Path(__file__).resolve().parents[3]

def _merge(a: dict, b: dict) -> dict:
    out = copy.deepcopy(a)
    for k, v in b.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


#: the bench every commissioning runs on: the average inverter with 1 us dead
#: time and device drops (switch 0.8 V + 50 mOhm, diode 1.0 V + 30 mOhm, as
#: tests/python/test_commission_map.py), the board's ADC (default board)
BENCH_INVERTER = {"model": "average", "dead_time": 1e-6, "v_th_sw": 0.8, "r_on_sw": 0.05,
                  "v_f_diode": 1.0, "r_diode": 0.03}


#: a low-voltage drive's bench: a MOSFET bridge under complementary PWM,
#: 0.5 us dead time. The device carrying the current outside a switch's
#: on-time is the other MOSFET conducting in reverse (synchronous
#: rectification: no threshold, its 20 mOhm); the body diode conducts only
#: within the dead time, which the dead-time model holds. (Modelled as a
#: 0.7 V body diode over the whole off-time, as before, the duty-dependent
#: threshold scaled rs's slope by 1 / (1 + 0.7 V / v_dc): R_s -2.8 % on
#: fabbri2022_ebike and _t51, +0.4 % and +0.03 % with the 0.7 V switched
#: off; docs/commissioning.md, rs "Limits".)
MOSFET_INVERTER = {"model": "average", "dead_time": 5e-7, "v_th_sw": 0.0, "r_on_sw": 0.02,
                   "v_f_diode": 0.0, "r_diode": 0.02}


@dataclass(frozen=True)
class Preset:
    """How a preset is commissioned: the procedures in order, the scenario's
    sections over the bench (its own i_max, the fmap grid ...), per
    procedure overrides (the star point needs the switching inverter and
    its sensing), the SIL time given each run."""

    procs: tuple[str, ...]
    sections: dict = field(default_factory=dict)
    per_proc: dict = field(default_factory=dict)
    ci_procs: tuple[str, ...] | None = None  # the CI test's (None: procs)


#: the star point's procedure: the switching inverter (the star signal
#: needs the PWM pattern), small device drops (docs/commissioning.md, star:
#: thresholds change the plant's star signal itself), the star channel of
#: sil/scenarios/fabbri_speed.json, no encoder in use
_STAR = {"inverter": {"model": "switching", "dead_time": 5e-7, "v_th_sw": 0.0, "r_on_sw": 0.02,
                      "v_f_diode": 0.0, "r_diode": 0.01},
         "sensors": {"star_full_scale": 13.0, "star_noise": 0.002, "star_tau": 2e-7},
         "board": {"preset": "g474_nucleo", "asym_edges": 1},
         "controller": {"pos_source": "dfc", "align_time": 0.1}}

#: the flux-map presets' bench (tests/python/test_commission_map.py): 9 x 5 grid
_FMAP = {"sensors": {"v_full_scale": 1000, "i_noise": 0.002, "v_noise": 0.1, "encoder_cpr": 4096},
         "controller": {"id_fmap_nd": 9, "id_fmap_nq": 5, "v_dc_max": 800, "v_dc_min": 200}}

PRESETS: dict[str, Preset] = {
    # Rubino 2020 Table I SPM: every value the DB-DFVC and its speed loop use
    "rubino2020_spm": Preset(("offset", "rs", "ldq", "poles", "enc", "flux", "mech"),
                             {"sensors": {"i_noise": 0.005, "encoder_cpr": 4096}},
                             # CI: the values the DB-DFVC's torque uses
                             ci_procs=("offset", "rs", "ldq", "enc", "flux")),
    # the Table 5.1 motor of Fabbri 2022: the linear values and the star point
    # (a low-voltage drive: MOSFETs, no threshold, their body diodes)
    "fabbri2022_t51": Preset(("offset", "rs", "ldq", "poles", "enc", "flux", "mech", "star"),
                             {"sensors": {"i_noise": 0.005, "encoder_cpr": 65536},
                              "inverter": MOSFET_INVERTER},
                             {"star": _STAR},
                             # CI: the star point, what Fabbri's position is made of
                             ci_procs=("offset", "star")),
    # the 1.1 kW SyR of Varatharajan 2022: R_s and the flux maps over the
    # current range of the paper's test (i_max 4.879 A), no magnet
    "syr_1k1": Preset(("offset", "rs", "fmap"),
                      {"sensors": {"v_full_scale": 1000, "i_noise": 0.002, "v_noise": 0.1,
                                   "encoder_cpr": 4096},
                       "controller": {"i_max": 4.879, "i_trip": 7.3185, "id_fmap_current": 4.879,
                                      "id_fmap_nd": 9, "id_fmap_nq": 5, "id_fmap_dwell": 0.012,
                                      "v_dc_max": 800, "v_dc_min": 200}}),
    # the other presets: their full commissioning's durations (--durations;
    # procedures that fail there are open points of docs/commissioning.md)
    "fabbri2022_ebike": Preset(("offset", "rs", "ldq", "poles", "enc", "flux", "mech", "star"),
                               {"sensors": {"i_noise": 0.005, "encoder_cpr": 65536},
                                "inverter": MOSFET_INVERTER}, {"star": _STAR}),
    "ipm_sat": Preset(("offset", "rs", "ldq", "poles", "enc", "flux", "mech", "fmap"),
                      _merge(_FMAP, {"controller": {
                          "i_max": 21.2, "i_trip": 31.8, "id_fmap_current": 21.2,
                          "id_fmap_dwell": 0.006, "v_dc_min": 50}})),
    # rs at i_max: R_s i at the default half of it is 3.6 V against the
    # inverter's 12.7 V error, and the slope's spread +-2 % over noise
    # levels; at i_max within 0.7 % (docs/commissioning.md, rs)
    "pmasyr_file": Preset(("offset", "rs", "ldq", "poles", "enc", "flux", "mech", "fmap"),
                          _merge(_FMAP, {"controller": {
                              "i_max": 8.0, "i_trip": 12.0, "id_fmap_current": 8.0,
                              "id_fmap_dwell": 0.006, "id_rs_current": 8.0}})),
}


#: the SIL time a procedure's run is first given [s] (the run goes on to
#: the scenario's end, so not much more than the procedure needs: the
#: switching inverter's runs are the costly ones); a run the procedure has
#: not ended in is run again with twice the time, up to MAX_TIME
PROC_TIME = {"offset": 0.2, "rs": 2.5, "ldq": 2.0, "poles": 8.0, "enc": 3.5, "flux": 3.5,
             "mech": 4.5, "star": 2.0, "fmap": 4.0}
MAX_TIME = 200.0

#: each drive parameter's range (the drive's table: PARAM_REQ and --params refuse outside)
_RANGE = {p["name"]: (p["min"], p["max"]) for p in params.tables()["params"]}


def scenario(preset: str, proc: str) -> dict:
    """The SIL scenario that runs `proc` on `preset`'s machine on the bench."""
    p = PRESETS[preset]
    sc = {"name": f"commission {preset}: {proc}", "duration": PROC_TIME.get(proc, 10.0),
          "machine": {"preset": preset}, "inverter": dict(BENCH_INVERTER),
          "mechanics": {"mode": "free"}, "sensors": {},
          "controller": {"law": "foc", "mode": "torque"},
          "references": {"torque": [{"type": "const", "value": 0.0}]}}
    sc = _merge(sc, p.sections)
    sc = _merge(sc, p.per_proc.get(proc, {}))
    sc["commission"] = [{"proc": proc}]
    return sc


def _sil(sil: Path, args: list[str], env_params: Path | None, timeout: float = 600.0):
    env = dict(os.environ)
    env.pop("FLUXDRIVE_PARAMS", None)
    if env_params is not None:
        args = args + ["--params", str(env_params)]
    return subprocess.run([str(sil), *args], capture_output=True, text=True, timeout=timeout,
                          env=env)


def _controller(sil: Path, sc_path: Path, params: Path | None) -> dict:
    r = _sil(sil, [str(sc_path), "--print-config"], params, 60.0)
    if r.returncode != 0:
        raise FluxdriveError(f"{sc_path}: --print-config failed: {r.stderr.strip()}")
    return json.loads(r.stdout)["controller"]


def _map_file(rec: dict, sc: dict, lambda_m: float, out: Path) -> tuple[Path, dict]:
    """The drive's map file from fmap's points (fluxdrive.commission_map),
    the PM flux at zero current the flux procedure's (0 without one); and
    the map's errors against the plant's (commission_map.errors)."""
    from fluxdrive import commission_map as cm
    from fluxdrive.fluxmap import blob

    c = sc["controller"]
    pts = cm.points_of(rec, lambda_m)
    ident, measured = cm.assemble(pts, int(c["id_fmap_nd"]), int(c["id_fmap_nq"]),
                                  int(rec["pole_pairs"]))
    # the flux at zero current is no measurement of the standstill method
    # (it sees changes from zero current): it is the PM flux, the flux
    # procedure's. A point's noise there (a few mVs on syr_1k1) would make
    # a reluctance machine's map a PM one (blob FLAG_PM: the drive then
    # magnetises along d, the low-inductance axis, and trips).
    jd = np.flatnonzero(np.abs(ident.i_d) < 1e-6)
    jq = np.flatnonzero(np.abs(ident.i_q) < 1e-6)
    if len(jd) and len(jq):
        ident.psi_d[jq[0], jd[0]] = lambda_m
        ident.psi_q[jq[0], jd[0]] = 0.0
    else:  # no node at zero current: the map shifted so that it holds lambda_m there
        ident.psi_d = ident.psi_d + (lambda_m - ident.pm_flux())
    ident.cache.clear()
    out.write_bytes(blob.to_bytes(ident))
    e = cm.errors(ident, measured, pts, cm.truth_of(sc, REPO), float(c["id_fmap_current"]))
    return out, {k: e[k] for k in ("map_rms", "map_worst", "mtpa_loss_worst")}


def commission_preset(sil: Path, preset: str, out: Path, procs: list[str] | None = None,
                      log=None) -> tuple[list[dict], dict]:
    """Commissions `preset` in the SIL; writes the parameter file `out` (and
    `out`'s stem + ``.fdmap`` after fmap). Returns (records as
    fluxdrive.commission.commission returns them, with the SIL times t0, t1;
    the parameter file)."""
    if preset not in PRESETS:
        raise FluxdriveError(f"no commissioning set up for the preset {preset}",
                             hint="known: " + ", ".join(PRESETS))
    procs = list(procs or PRESETS[preset].procs)
    out = Path(out)
    log = log or sys.stdout
    records: list[dict] = []
    pf: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for k, name in enumerate(procs):
            sc = scenario(preset, name)
            sc_path = tmp / f"{name}.json"
            sc_path.write_text(json.dumps(sc))
            pfile = tmp / f"params_{k}.json"  # what the drive holds so far
            pfile.write_text(json.dumps({kk: v for kk, v in pf.items() if kk != "identified"}))
            # the parameters in force, for a correction (relative) or fmap
            need = name == "fmap" or any(res.relative for res in results_of(name))
            ctrl = _controller(sil, sc_path, pfile) if need else {}
            summ = tmp / f"{name}.sum.json"
            while True:
                r = _sil(sil, [str(sc_path), "--summary", str(summ)], pfile)
                if r.returncode != 0:
                    raise FluxdriveError(f"{preset} {name}: the SIL failed: "
                                         f"{r.stderr.strip()[-400:]}")
                c = next(x for x in json.loads(summ.read_text())["commission"]
                         if x["proc"] == name)
                if c["t1"] >= 0.0 or sc["duration"] >= MAX_TIME:  # ended (or given up)
                    break
                sc["duration"] *= 2.0
                sc_path.write_text(json.dumps(sc))
            rec: dict[str, Any] = {"proc": name, "status": c["status"], "phase": 0,
                                   "results": c["result"], "named": {}, "written": {},
                                   # not ended within MAX_TIME: the time it ran
                                   "duration": (c["t1"] if c["t1"] >= 0.0 else sc["duration"])
                                   - c["t0"], "t0": c["t0"], "t1": c["t1"],
                                   "fault": c["fault"], "i_peak": c["i_peak"], "move": c["move"]}
            records.append(rec)
            print(f"[{k + 1}/{len(procs)}] {preset:<16} {name:<8} {c['status']:<8} "
                  f"{rec['duration']:7.3f} s (SIL)" + (f" faults {c['fault']}" if c["fault"] else ""),
                  file=log, flush=True)
            if c["status"] != "done":
                break
            # written into the drive as the CAN command writes them (RESULTS);
            # a value outside the parameter's range (the drive refuses it:
            # over CAN the PARAM_REQ's rejection stops the run) is reported
            # and left out, and the run goes on
            for res in results_of(name):
                rec["named"][res.name] = c["result"][res.index]
                if res.param is not None:
                    v = c["result"][res.index]
                    v = (ctrl[res.param] + v) if res.relative else v
                    lo, hi = _RANGE[res.param]
                    if lo <= v <= hi:
                        rec["written"][res.param] = v
                    else:
                        rec.setdefault("refused", {})[res.param] = v
                        print(f"    {res.param} = {v:.6g} outside [{lo:g}, {hi:g}]: not written",
                              file=log, flush=True)
            if name == "fmap":
                lam = pf.get("lambda_m", 0.0)
                c["pole_pairs"] = pf.get("pole_pairs", ctrl["pole_pairs"])
                mp, rec["map_errors"] = _map_file(c, sc, lam, out.with_suffix(".fdmap"))
                rec["written"]["map"] = mp.name  # relative to the parameter file's folder
            pf = parameter_file(records)
    pf = parameter_file(records)
    for rec in records:  # the SIL's own times, not the host's
        pf["identified"][rec["proc"]].update(t0=rec["t0"], t1=rec["t1"], i_peak=rec["i_peak"],
                                             move=rec["move"])
    out.write_text(json.dumps(pf, indent=1) + "\n", encoding="utf-8")
    return records, pf


def durations(records: list[dict], preset: str, out=None) -> float:
    """Prints each procedure's SIL duration (t1 - t0) and the total."""
    out = out or sys.stdout
    total = 0.0
    for rec in records:
        total += rec["duration"]
        print(f"{preset:<16} {rec['proc']:<8} {rec['status']:<8} {rec['duration']:8.3f} s", file=out)
    print(f"{preset:<16} {'total':<8} {'':<8} {total:8.3f} s", file=out)
    return total


def truth(sil: Path, preset: str) -> dict[str, float]:
    """The plant's truth for the report (fluxdrive.commission.truth_from_sil)."""
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "sc.json"
        p.write_text(json.dumps(scenario(preset, PRESETS[preset].procs[0])))
        return truth_from_sil(sil, p)


# ---------------------------------------------------------------- tables
MD_BEGIN = "<!-- commission-table:begin (fluxdrive commission --sil-preset all --markdown) -->"
MD_END = "<!-- commission-table:end -->"


def _g(x: float) -> str:
    return f"{x:.4g}"


def markdown(sil: Path, presets: list[str], log=None) -> str:
    """Per machine: each identified value, the plant's, the error; each
    procedure's status and SIL time; the map's errors (fmap)."""
    out = []
    for preset in presets:
        with tempfile.TemporaryDirectory() as d:
            records, _ = commission_preset(sil, preset, Path(d) / "p.json", log=log)
        tr = truth(sil, preset)
        # the encoder's: the correction's truth is the plant's offset (the
        # presets' drive holds 0), electrical
        tr.setdefault("enc_offset_error", float(np.radians(tr.get("offset_deg_e", 0.0))))
        total = sum(r["duration"] for r in records)
        out += [f"**{preset}** ({', '.join(r['proc'] for r in records)}; "
                f"{_g(total)} s of SIL time)", "",
                "| procedure | value | unit | identified | true | error | error % |",
                "|---|---|---|---|---|---|---|"]
        for rec in records:
            for res in results_of(rec["proc"]):
                v = rec["named"].get(res.name)
                if v is None:
                    continue
                t = tr.get(res.param or res.name, tr.get(res.name))
                err = f"{100.0 * (v - t) / t:+.2f}" if t not in (None, 0.0) else "-"
                out.append(f"| {rec['proc']} | {res.name} | {res.unit} | {_g(v)} | "
                           f"{'-' if t is None else _g(t)} | {'-' if t is None else _g(v - t)} | "
                           f"{err} |")
            if "map_errors" in rec:
                e = rec["map_errors"]
                out.append(f"| fmap | map rms / worst, MTPA loss | % | {100 * e['map_rms']:.2f} / "
                           f"{100 * e['map_worst']:.2f}, {100 * e['mtpa_loss_worst']:.3f} | "
                           f"(limits 3 / 6, 1) | | |")
            faults = f", {', '.join(rec['fault'])}" if rec.get("fault") else ""
            out.append(f"| {rec['proc']} | status | s | {rec['status']}{faults} "
                       f"({_g(rec['duration'])} s) | | | |")
        out.append("")
    return "\n".join(out)


def write_markdown(path: Path, body: str, check: bool) -> bool:
    """Writes `body` between the markers of `path`; check: True when it is
    there already (nothing written)."""
    text = path.read_text(encoding="utf-8")
    if MD_BEGIN not in text or MD_END not in text:
        raise FluxdriveError(f"{path}: no table markers", hint=f"add the lines\n  {MD_BEGIN}\n  {MD_END}")
    a, rest = text.split(MD_BEGIN, 1)
    _, b = rest.split(MD_END, 1)
    new = a + MD_BEGIN + "\n" + body + MD_END + b
    if check:
        return new == text
    path.write_text(new, encoding="utf-8")
    return True


# ------------------------------------------------------------ acceptance
#: the paper acceptance tests each commissioned machine runs again, with
#: FLUXDRIVE_PARAMS: (test file, the tests on this machine). Left out: the
#: tests on other machines or on no SIL run (Varatharajan's gain
#: comparison, Fabbri's convergence plants, harmonic with the e-bike, the
#: other laws), those whose scenarios set the drive's parameters wrong on
#: purpose (the detuned Rubino ramps: the file would undo the detuning;
#: Varatharajan's robustness scales the drive's map on purpose and needs
#: the preset's as its reference) and the plant check.
ACCEPTANCE: dict[str, list[str]] = {
    "rubino2020_spm": [
        "tests/python/test_rubino2020.py::" + t for t in (
            "test_torque_step_deadbeat", "test_torque_step_pi", "test_step_settles_on_the_reference",
            "test_torque_step_deadbeat_32khz", "test_torque_reversal", "test_fw_current_limit",
            "test_fw_load_angle_limit", "test_fw_torque_not_above_capability",
            "test_fw_torque_reaches_capability", "test_torque_bandwidth_1500hz",
            "test_speed_control_0_to_1200", "test_flux_weakening_ramp_full_voltage")],
    "syr_1k1": [
        "tests/python/test_varatharajan2022.py::" + t for t in (
            "test_bandwidth_uniform_with_proposed_gains_16khz",
            "test_bandwidth_uniform_with_proposed_gains_5khz",
            "test_state_of_the_art_gains_shift_the_poles", "test_speed_step_mtpa_fw_mtpv",
            "test_steady_mtpv_limit", "test_sine_torque_online_mtpa")],
    "fabbri2022_t51": [
        "tests/python/test_fabbri2022.py::test_closed_loop_on_the_ivd_position",
        "tests/python/test_fabbri2022.py::test_full_ivd_removes_the_load_phase_shift"],
}

#: the cheap subset CI runs (tests/python/test_commission_loop.py)
ACCEPTANCE_CI: dict[str, list[str]] = {
    "rubino2020_spm": ["tests/python/test_rubino2020.py::test_torque_step_deadbeat",
                       "tests/python/test_rubino2020.py::test_torque_reversal"],
    "syr_1k1": ["tests/python/test_varatharajan2022.py::test_speed_step_mtpa_fw_mtpv"],
    "fabbri2022_t51": ["tests/python/test_fabbri2022.py::test_closed_loop_on_the_ivd_position"],
}


def accept(params: Path, tests: list[str], sil: Path | None = None,
           extra: list[str] | None = None) -> subprocess.CompletedProcess:
    """Runs `tests` (pytest node ids) with FLUXDRIVE_PARAMS=params."""
    env = dict(os.environ, FLUXDRIVE_PARAMS=str(Path(params).resolve()))
    if sil is not None:
        env["FLUXDRIVE_SIL"] = str(sil)
    env["PYTHONPATH"] = os.pathsep.join([str(REPO / "tools" / "src"), env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           *(extra or []), *tests], cwd=REPO, env=env, text=True,
                          capture_output=True)


def main(args) -> int:
    from fluxdrive.sil import locate_sil

    sil = locate_sil(args.sil_bin)
    presets = list(PRESETS) if args.sil_preset == "all" else [args.sil_preset]
    if args.markdown or args.check_markdown:
        path = Path(args.markdown or args.check_markdown)
        same = write_markdown(path, markdown(sil, presets, open(os.devnull, "w")),
                              bool(args.check_markdown))
        if not same:
            print(f"{path}: the commissioning tables are out of date (regenerate: fluxdrive "
                  f"commission --sil-preset all --markdown {path})", file=sys.stderr)
        return 0 if same else 1
    ok = True
    totals = {}
    for preset in presets:
        out = Path(args.out) if len(presets) == 1 else Path(args.out).with_name(
            f"{Path(args.out).stem}_{preset}.json")
        records, _ = commission_preset(sil, preset, out, args.procs or None)
        ok = ok and all(r["status"] == "done" for r in records) and \
            len(records) == len(args.procs or PRESETS[preset].procs)
        if not args.durations:
            print()
            report(records, truth(sil, preset))
            print(f"\nparameter file: {out}")
        totals[preset] = records
        if args.accept:
            tests = ACCEPTANCE[preset] if args.accept == "all" else ACCEPTANCE_CI[preset]
            print(f"\nthe acceptance tests on {preset} with FLUXDRIVE_PARAMS={out}:", flush=True)
            r = accept(out, tests, sil, ["-rfE"])
            print(r.stdout[-6000:], r.stderr[-2000:], sep="", flush=True)
            ok = ok and r.returncode == 0
    if args.durations:
        print(f"\n{'preset':<16} {'proc':<8} {'status':<8} {'SIL time':>10}")
        for preset, records in totals.items():
            durations(records, preset)
    return 0 if ok else 1
