"""``fluxdrive commission``: identifies the motor over CAN (issue 25, point 3).

Runs the drive's identification procedures one after the other (CMD_PROC:
each alone, the drive disabled: the offsets, then it, then the gates off;
docs/commissioning.md), follows each through TM_PROC (status, phase, its
eight results, one per frame) with a plain-text progress line, writes what
each found back into the drive as parameters (PARAM_REQ), writes a
parameter file and prints a report::

    fluxdrive commission --interface socketcan --channel can0          # a board
    fluxdrive commission offset --sil sil/scenarios/can_demo.json      # the SIL, with its truth

With ``--sil SCENARIO`` it starts ``fluxdrive-sil SCENARIO --can
socketcand:0 --realtime`` itself and the report adds the plant's truth and
the error of each value (``fluxdrive-sil --print-truth`` when the runner
has it, else ``--print-config`` and the scenario's sensor and injected
current offsets).

What a procedure's results mean is its row's (proc.h, each row's
publish()); :data:`RESULTS` maps each result index to a name, a unit and
the drive parameter it is written to (None: reported, not written).
Adding a procedure to the commissioning is one entry there; one in
:data:`ORDER` if it must run before or after another.
"""

from __future__ import annotations

import argparse
import json
import re
import select
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fluxdrive import params
from fluxdrive.errors import FluxdriveError

#: the order a full commissioning runs the identification procedures in, as
#: far as the drive has them (each needs the ones before: the offsets, R_s
#: for the inductances' voltage, the poles and encoder before the flux at
#: speed, the mechanics last; the flux maps after the linear values).
#: Procedures the drive has that are not listed run after these, in the
#: drive's order.
ORDER = ("offset", "rs", "ldq", "poles", "enc", "flux", "mech", "fmap")


@dataclass(frozen=True)
class Result:
    """Result `index` of a procedure (proc_telemetry_t.result[index])."""

    index: int
    name: str  # the report's and the parameter file's name
    unit: str
    param: str | None = None  # drive parameter (PARAM_REQ name) it is written to; None: none
    relative: bool = False  # written as the parameter in force plus the result (a correction)


#: procedure -> its results, from each row's publish() (proc.h). The
#: identification procedures being written for issue 25 add their rows
#: here as they land (e.g. "rs": [Result(0, "rs", "ohm", "rs")]); a
#: procedure without an entry has its eight raw results reported and
#: nothing written.
RESULTS: dict[str, list[Result]] = {
    # proc_offset.c: the three current-sensor offsets [A] (measured again
    # at every enable: no parameter holds them)
    "offset": [Result(0, "offset_a", "A"), Result(1, "offset_b", "A"), Result(2, "offset_c", "A")],
    # proc_star.c: the star point's a, b of (3.7) (normalised to v_dc), p =
    # b/a, the fit's rms residual over |a| (truth: --print-truth's star.a,
    # star.b)
    "star": [Result(0, "star.a", "", "dfc_a"), Result(1, "star.b", "", "dfc_b"),
             Result(2, "star_p", ""), Result(4, "star_residual", "")],
    # proc_rs.c: R_s (the slope over the levels above the knee), the
    # inverter's voltage error at the top level, the knee current
    "rs": [Result(0, "machine.rs", "ohm", "rs"), Result(1, "v_err_top", "V"),
           Result(2, "v_err_knee", "A")],
    # proc_ldq.c: L_d, L_q at the bias (incremental inductances)
    "ldq": [Result(0, "machine.ld", "H", "ld"), Result(1, "machine.lq", "H", "lq")],
    # proc_poles.c: pole pairs (rounded; the residue in result 3), polarity
    "poles": [Result(0, "machine.pole_pairs", "", "pole_pairs"), Result(1, "polarity", ""),
              Result(3, "poles_residue", "")],
    # proc_enc.c: the offset's correction [rad electrical] on the one in
    # force (theta_e = p theta_m - enc_offset, pos_encoder.c), the direction
    "enc": [Result(0, "enc_offset_error", "rad", "enc_offset", relative=True),
            Result(1, "encoder.direction", "")],
    # proc_flux.c: lambda_m (both directions' mean)
    "flux": [Result(0, "machine.lambda_m", "Vs", "lambda_m")],
    # proc_mech.c: J, Coulomb friction, viscous friction (the drive's
    # `friction` is the viscous B of the Kalman filter's model (4.46))
    "mech": [Result(0, "mechanics.j", "kg m^2", "inertia"), Result(1, "mechanics.coulomb", "N m"),
             Result(2, "mechanics.viscous", "N m s/rad", "friction")],
}


def results_of(proc: str) -> list[Result]:
    return RESULTS.get(proc) or [Result(k, f"{proc}_result{k}", "") for k in range(8)]


def default_procs(available: list[str]) -> list[str]:
    """Every identification procedure the drive has, in ORDER first."""
    return [p for p in ORDER if p in available] + [p for p in available if p not in ORDER]


# ------------------------------------------------------------------ truth
def _profile_const(v: Any) -> float | None:
    """A profile's value when it is a constant (a number or one step at t=0)."""
    if isinstance(v, (int, float)):
        return float(v)
    return None


def truth_from_sil(sil: Path, scenario: Path) -> dict[str, float]:
    """The plant's true values by result name: ``--print-truth`` when the
    runner has it (its flat keys), else the resolved machine
    (``--print-config``) and the current offsets the scenario puts in the
    sensors (``sensors.offset_error`` plus constant ``inject.current``
    offsets)."""
    truth: dict[str, float] = {}
    r = subprocess.run([str(sil), str(scenario), "--print-truth"], capture_output=True, text=True,
                       timeout=60)
    if r.returncode == 0 and r.stdout.strip().startswith("{"):
        def flat(o: Any, prefix: str = "") -> None:
            for k, v in o.items():
                if isinstance(v, dict):
                    flat(v, f"{prefix}{k}.")
                elif isinstance(v, (int, float)) and not isinstance(v, bool):
                    truth.setdefault(k, float(v))
                    truth[prefix + k] = float(v)
        flat(json.loads(r.stdout))
    r = subprocess.run([str(sil), str(scenario), "--print-config"], capture_output=True, text=True,
                       timeout=60)
    if r.returncode != 0:
        raise FluxdriveError(f"{sil} {scenario} --print-config failed: {r.stderr.strip()}")
    cfg = json.loads(r.stdout)
    for k, v in cfg.get("machine", {}).items():
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            truth.setdefault(k, float(v))
    sc = json.loads(Path(scenario).read_text(encoding="utf-8"))
    off = list(sc.get("sensors", {}).get("offset_error", [0.0, 0.0, 0.0]))
    for inj in sc.get("inject", {}).get("current", []):
        v = _profile_const(inj.get("value"))
        if inj.get("kind") == "offset" and v is not None and "active" not in inj:
            off["abc".index(inj["channel"])] += v
    for k, ch in enumerate("abc"):
        truth.setdefault(f"offset_{ch}", float(off[k]))
    return truth


# -------------------------------------------------------------------- SIL
class SilProcess:
    """fluxdrive-sil SCENARIO --can socketcand:0 --realtime on a free port."""

    def __init__(self, sil: Path, scenario: Path, node: int) -> None:
        self.proc = subprocess.Popen([str(sil), str(scenario), "--can", "socketcand:0", "--realtime",
                                      "--node", str(node)], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True)
        ready, _, _ = select.select([self.proc.stderr], [], [], 30.0)
        line = self.proc.stderr.readline() if ready else ""
        m = re.search(r"127\.0\.0\.1:(\d+)", line)
        if not m:
            self.stop()
            raise FluxdriveError(f"the SIL did not start its CAN server: {line.strip()}")
        self.port = int(m.group(1))

    def stop(self) -> str:
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            _, err = self.proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return err or ""


# --------------------------------------------------------------- progress
class Progress:
    """A plain-text progress line per procedure: [k/n] name, a bar over the
    procedures, its status and phase, the time it has taken."""

    def __init__(self, procs: list[str], out=sys.stdout) -> None:
        self.procs = procs
        self.out = out
        self.t0 = time.monotonic()

    def __call__(self, k: int, st) -> None:
        n = len(self.procs)
        width = 20
        fill = int(width * (k + (1.0 if st.ended else 0.5)) / n)
        bar = "#" * fill + "." * (width - fill)
        print(f"[{bar}] {k + 1}/{n} {self.procs[k]:<8} {st.status:<8} phase {st.phase:3d} "
              f"({time.monotonic() - self.t0:6.2f} s)", file=self.out, flush=True)


# ------------------------------------------------------------------- run
def commission(drv, procs: list[str], write: bool = True, timeout: float = 120.0,
               out=sys.stdout) -> list[dict]:
    """Runs `procs` in turn on an open Drive; returns one record per
    procedure run ({proc, status, phase, results, named, written,
    duration}). Stops at the first that does not end done."""
    st = drv.status()
    if st["state_name"] == "fault":
        raise FluxdriveError(f"the drive is in fault ({', '.join(st['fault_names'])}): clear it first")
    if st["cmd_enabled"]:
        drv.disable()
    progress = Progress(procs, out)
    records = []
    for k, name in enumerate(procs):
        t0 = time.monotonic()
        drv.identify(name)
        end = drv.wait_proc(name, timeout=timeout, after=t0, progress=lambda s, k=k: progress(k, s))
        rec: dict[str, Any] = {"proc": name, "status": end.status, "phase": end.phase,
                               "results": end.results, "named": {}, "written": {},
                               "duration": time.monotonic() - t0}
        records.append(rec)
        if end.status == "refused":  # this drive's set cannot run it (no star point ...)
            print(f"{name}: refused by the drive's parameter set; skipped", file=out)
            continue
        if end.status != "done":
            faults = drv.status()["fault_names"]
            print(f"{name}: {end.status}" + (f" (faults: {', '.join(faults)})" if faults else "")
                  + "; the commissioning stops here", file=out)
            break
        for r in results_of(name):
            rec["named"][r.name] = end.results[r.index]
            if r.param is not None and write:
                v = end.results[r.index]
                if r.relative:
                    v = drv.get_param(r.param) + v
                rec["written"][r.param] = drv.set_param(r.param, v)
    return records


def parameter_file(records: list[dict]) -> dict:
    """The parameter file: the written parameters by the parameter table's
    names (docs/parameters.md; what ``fluxdrive-sil --params`` and
    PARAM_REQ take), and every result, by procedure, under "identified"
    (the record: ``--params`` ignores it)."""
    out: dict[str, Any] = {}
    for rec in records:
        out.update(rec["written"])
    out["identified"] = {rec["proc"]: {"status": rec["status"], "duration": round(rec["duration"], 3),
                                       "results": rec["results"], **rec["named"]} for rec in records}
    return out


def report(records: list[dict], truth: dict[str, float] | None, out=sys.stdout) -> None:
    head = f"{'procedure':<10} {'value':<14} {'identified':>12} {'unit':<6} {'parameter':<10}"
    if truth is not None:
        head += f" {'true':>12} {'error':>10} {'error %':>8}"
    print(head, file=out)
    for rec in records:
        for r in results_of(rec["proc"]):
            v = rec["named"].get(r.name)
            if v is None:
                continue
            line = f"{rec['proc']:<10} {r.name:<14} {v:12.6g} {r.unit:<6} {r.param or '-':<10}"
            t = None if truth is None else truth.get(r.param or r.name, truth.get(r.name))
            if t is not None:
                rel = f"{100.0 * (v - t) / t:8.2f}" if t != 0.0 else f"{'-':>8}"
                line += f" {t:12.6g} {v - t:10.3g} {rel}"
            print(line, file=out)
        print(f"{rec['proc']:<10} {'status':<14} {rec['status']:>12} ({rec['duration']:.2f} s)", file=out)


def speed_step(drv, rpm: float, duration: float = 1.5, law: str | None = None,
               period: float = 0.02, out=None) -> dict:
    """After the commissioning, on the values it loaded: speed mode, enable,
    a step to `rpm`, the speed sampled every `period` s for `duration` s
    (the drive's own time, TM_SPEED's stamp where the SIL gives it), then
    disabled. Prints the tracking (reference, speed, error) and returns
    {t, ref, speed, faults, final_rpm, error, t_90}: error the mean over the
    last fifth against the reference, t_90 the time to 90 % of the step."""
    out = out or sys.stdout
    if law is not None:
        drv.set_law(law)
    drv.set_mode("speed")
    drv.set_speed(0.0)
    drv.enable()
    drv.set_speed(rpm)
    t_host0 = time.monotonic()
    t_frame0 = drv.frame_time("TM_SPEED")
    ts, ref, sp = [], [], []
    faults: list[str] = []
    while time.monotonic() - t_host0 < duration:
        v = drv.read_telemetry(1.0, ("TM_SPEED",))
        ft = drv.frame_time("TM_SPEED")
        ts.append(ft - t_frame0 if ft is not None and t_frame0 is not None
                  else time.monotonic() - t_host0)
        ref.append(float(rpm))
        sp.append(float(v["speed_rpm"]))
        time.sleep(period)
    st = drv.status()
    faults = st["fault_names"]
    drv.disable()
    n = max(1, len(sp) // 5)
    final = sum(sp[-n:]) / n
    err = (final - rpm) / rpm if rpm else final
    t90 = next((t for t, s_ in zip(ts, sp) if abs(s_) >= 0.9 * abs(rpm)), float("nan"))
    print(f"\nspeed step 0 -> {rpm:g} rpm on the commissioned values:", file=out)
    print(f"{'t [s]':>8} {'ref [rpm]':>10} {'speed [rpm]':>12} {'error [rpm]':>12}", file=out)
    step = max(1, len(ts) // 15)
    for k in list(range(0, len(ts), step)) + ([len(ts) - 1] if (len(ts) - 1) % step else []):
        print(f"{ts[k]:8.3f} {ref[k]:10.1f} {sp[k]:12.2f} {sp[k] - ref[k]:12.2f}", file=out)
    print(f"final {final:.2f} rpm (error {100 * err:+.2f} %), 90 % of the step at "
          f"{t90:.3f} s, faults: {', '.join(faults) or 'none'}", file=out)
    return {"t": ts, "ref": ref, "speed": sp, "faults": faults, "final_rpm": final, "error": err,
            "t_90": t90}


def main(args: argparse.Namespace) -> int:
    from fluxdrive.can.drive import Drive, open_bus
    from fluxdrive.sil import locate_sil

    if args.sil_preset:  # offline, in the SIL (fluxdrive.commission_sil)
        from fluxdrive import commission_sil
        return commission_sil.main(args)
    available = params.ident_procs()
    procs = args.procs or default_procs(available)
    unknown = [p for p in procs if p not in available]
    if unknown:
        raise FluxdriveError(f"not an identification procedure of this drive: {', '.join(unknown)}",
                             hint="known: " + ", ".join(available))
    sil = None
    truth = None
    port = args.port
    if args.sil:
        sil_bin = locate_sil(args.sil_bin)
        truth = truth_from_sil(sil_bin, Path(args.sil))
        sil = SilProcess(sil_bin, Path(args.sil), args.node)
        port = sil.port
    ok = False
    try:
        try:
            bus = open_bus(args.channel, args.interface, args.host, port)
        except Exception as exc:  # python-can raises many kinds
            raise FluxdriveError(f"cannot open the CAN bus ({args.interface} {args.channel}): {exc}") from None
        with Drive(node=args.node, bus=bus, reply_timeout=args.reply_timeout, retries=args.retries) as drv:
            drv.heartbeat(args.heartbeat)  # keeps the command timeout away while they run
            records = commission(drv, procs, write=not args.no_write, timeout=args.timeout)
            ok = all(r["status"] in ("done", "refused") for r in records) and \
                len(records) == len(procs)
            tracking = None
            if args.then_speed is not None and ok:  # from a blank drive to speed control
                tracking = speed_step(drv, args.then_speed, args.speed_time, args.law)
                ok = not tracking["faults"] and abs(tracking["error"]) <= args.speed_tol
        bus.shutdown()
        pf = parameter_file(records)
        Path(args.out).write_text(json.dumps(pf, indent=1) + "\n", encoding="utf-8")
        print()
        report(records, truth)
        print(f"\nparameter file: {args.out}")
    finally:
        if sil is not None:
            sil.stop()
    return 0 if ok else 1


def add_parser(sub) -> None:
    from fluxdrive.can.cli import add_bus_args

    p = sub.add_parser("commission", help="identify the motor over CAN: run the identification "
                       "procedures, load the results into the drive, write a parameter file, report")
    p.add_argument("procs", nargs="*", metavar="PROC",
                   help="procedures in the order to run (default: every identification procedure "
                   "the drive has: " + ", ".join(ORDER) + " as far as they exist)")
    add_bus_args(p)
    p.add_argument("--sil", metavar="SCENARIO", help="start fluxdrive-sil SCENARIO --can socketcand "
                   "--realtime and report the plant's truth beside each value")
    p.add_argument("--sil-bin", metavar="PATH", help="the fluxdrive-sil to start (default: "
                   "$FLUXDRIVE_SIL, else build/host-release)")
    p.add_argument("--sil-preset", metavar="PRESET", help="commission a preset offline in the SIL "
                   "(each procedure a SIL run, the results so far over the drive; 'all': every "
                   "preset set up in fluxdrive.commission_sil) and write the parameter file")
    p.add_argument("--durations", action="store_true", help="with --sil-preset: print each "
                   "procedure's SIL time (t1 - t0) and the total per preset")
    p.add_argument("--accept", nargs="?", const="ci", choices=("ci", "all"), help="with "
                   "--sil-preset: then run the preset's paper acceptance tests with "
                   "FLUXDRIVE_PARAMS=the file (ci: the cheap subset, all: every one on the machine)")
    p.add_argument("--markdown", metavar="MD", help="with --sil-preset: write the per-machine "
                   "tables (value, true, identified, error) between MD's markers")
    p.add_argument("--check-markdown", metavar="MD", help="with --sil-preset: fail if MD's "
                   "tables are not what --markdown writes")
    p.add_argument("--out", default="commission.json", help="parameter file (default commission.json)")
    p.add_argument("--no-write", action="store_true", help="do not load the results into the drive")
    p.add_argument("--then-speed", type=float, metavar="RPM", help="then, on the values loaded: "
                   "speed mode, enable, a step to RPM, print the speed tracking, disable (exit "
                   "status 1 on a fault or a final speed off by more than --speed-tol)")
    p.add_argument("--speed-time", type=float, default=1.5, help="the speed step's length [s] "
                   "(default 1.5)")
    p.add_argument("--speed-tol", type=float, default=0.02, help="final speed's tolerance, "
                   "relative (default 0.02)")
    p.add_argument("--law", help="the law for the speed step (default: the drive's)")
    p.add_argument("--timeout", type=float, default=120.0, help="per procedure [s] (default 120)")
    p.add_argument("--heartbeat", type=float, default=0.05, help="HOST_HB period [s] (default 0.05)")
    p.add_argument("--reply-timeout", type=float, default=1.0, help="per request [s] (default 1)")
    p.add_argument("--retries", type=int, default=2, help="resends of an unanswered request (default 2)")
    p.set_defaults(func=main)
