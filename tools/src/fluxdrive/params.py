"""``fluxdrive params``: the drive's parameter table and named values, as the
firmware defines them (firmware/app/drive_param_table.h and drive_enums.h,
printed by ``fluxdrive-sil --print-params``), rendered into every place that
must agree with them:

* ``firmware/app/can/fluxdrive.dbc``: the value tables (``VAL_``) of
  reply_param, reply_result, the laws, modes, states and the CMD_STATE
  "keep" value, and the comment that lists the fault bits;
* ``tools/src/fluxdrive/drive_tables.json``: what the Python tools use for
  names (laws, modes, states, faults, parameters) - :func:`tables`;
* ``docs/parameters.md``: the parameter table for people.

``--write`` regenerates them; ``--check`` (CTest ``params/agreement``)
fails, naming the file, when one differs from what the firmware says.
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
from functools import lru_cache
from pathlib import Path

from fluxdrive.errors import FluxdriveError

PACKAGE_TABLES = Path(__file__).with_name("drive_tables.json")
DBC_REL = Path("firmware/app/can/fluxdrive.dbc")
DOC_REL = Path("docs/parameters.md")
TABLES_REL = Path("tools/src/fluxdrive/drive_tables.json")

# DBC message ids of the signals whose value tables come from the firmware
CMD_STATE, CMD_PROC, REPLY, STATUS, TM_PROC, HEARTBEAT = 256, 368, 384, 512, 880, 1792
#: CMD_PROC.cmd_proc: stops the identification running; TM_PROC.proc_id: none yet
PROC_STOP = 255


@lru_cache(maxsize=1)
def tables() -> dict:
    """The drive's table as packaged with the tools (generated, checked)."""
    return json.loads(PACKAGE_TABLES.read_text(encoding="utf-8"))


def law_ids() -> dict[str, int]:
    return {n: i for i, n in enumerate(tables()["laws"])}


def mode_ids() -> dict[str, int]:
    return {n: i for i, n in enumerate(tables()["modes"])}


def pos_source_ids() -> dict[str, int]:
    return {n: i for i, n in enumerate(tables()["pos_sources"])}


def state_names() -> dict[int, str]:
    return dict(enumerate(tables()["states"]))


def fault_names(bits: int) -> list[str]:
    return [n for b, n in enumerate(tables()["faults"]) if bits & (1 << b)]


def proc_ids() -> dict[str, int]:
    """Every procedure of the firmware's table (proc.h PROC_LIST) by name."""
    return {p["name"]: i for i, p in enumerate(tables()["procs"])}


def ident_procs() -> list[str]:
    """The identification procedures (PROC_CAP_IDENT: CMD_PROC runs them), in table order."""
    return [p["name"] for p in tables()["procs"] if p["ident"]]


def keep() -> int:
    return int(tables()["can_keep"])


def from_sil(sil: Path) -> dict:
    """The table as the built firmware prints it."""
    r = subprocess.run([str(sil), "--print-params"], capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        raise FluxdriveError(f"{sil} --print-params failed: {r.stderr.strip()}", exit_code=1)
    return json.loads(r.stdout)


# ------------------------------------------------------------------ render
def _val(msg: int, sig: str, pairs: list[tuple[int, str]]) -> str:
    return f"VAL_ {msg} {sig} " + " ".join(f'{k} "{v}"' for k, v in pairs) + " ;"


def dbc_lines(t: dict) -> dict[str, str]:
    """Generated DBC lines, keyed by the prefix that identifies the line."""
    k = t["can_keep"]
    laws = list(enumerate(t["laws"]))
    modes = list(enumerate(t["modes"]))
    states = list(enumerate(t["states"]))
    params = [(p["id"], p["name"]) for p in sorted(t["params"], key=lambda p: p["id"])]
    params += [(p["id"], p["name"]) for p in t["can_params"]]
    faults = ", ".join(f"{b} {n}" for b, n in enumerate(t["faults"]))
    procs = [(i, p["name"]) for i, p in enumerate(t["procs"])]
    out = {
        f"VAL_ {CMD_PROC} cmd_proc ": _val(CMD_PROC, "cmd_proc", procs + [(PROC_STOP, "stop")]),
        f"VAL_ {TM_PROC} proc_id ": _val(TM_PROC, "proc_id", procs + [(PROC_STOP, "none")]),
        f"VAL_ {CMD_STATE} enable ": _val(CMD_STATE, "enable", [(0, "disable"), (1, "enable"),
                                                                  (k, "keep")]),
        f"VAL_ {CMD_STATE} mode ": _val(CMD_STATE, "mode", modes + [(k, "keep")]),
        f"VAL_ {CMD_STATE} law ": _val(CMD_STATE, "law", laws + [(k, "keep")]),
        f"VAL_ {REPLY} reply_result ": _val(REPLY, "reply_result", list(enumerate(t["can_results"]))),
        f"VAL_ {REPLY} reply_param ": _val(REPLY, "reply_param", params),
        f"VAL_ {STATUS} state ": _val(STATUS, "state", states),
        f"VAL_ {STATUS} ctrl_mode ": _val(STATUS, "ctrl_mode", modes),
        f"VAL_ {STATUS} ctrl_law ": _val(STATUS, "ctrl_law", laws),
        f"VAL_ {HEARTBEAT} hb_state ": _val(HEARTBEAT, "hb_state", states),
        f"CM_ SG_ {CMD_STATE} mode ": f'CM_ SG_ {CMD_STATE} mode "'
        + ", ".join(f"{i} {n}" for i, n in modes) + f', {k} keep";',
        f"CM_ SG_ {CMD_STATE} law ": f'CM_ SG_ {CMD_STATE} law "'
        + ", ".join(f"{i} {n}" for i, n in laws)
        + f', {k} keep; a law change takes effect with the gates off; a law the machine '
        'cannot run is answered unavailable";',
        f"CM_ SG_ {STATUS} faults ": f'CM_ SG_ {STATUS} faults "latched fault bits: {faults}";',
    }
    return out


def render_dbc(text: str, t: dict) -> str:
    gen = dbc_lines(t)
    seen = set()
    lines = []
    for line in text.splitlines():
        key = next((p for p in gen if line.startswith(p)), None)
        if key is not None:
            lines.append(gen[key])
            seen.add(key)
        else:
            lines.append(line)
    missing = [p.strip() for p in gen if p not in seen]
    if missing:
        raise FluxdriveError(f"{DBC_REL}: no line to regenerate for: {', '.join(missing)}",
                             exit_code=1)
    return "\n".join(lines) + "\n"


def _num(x: float) -> str:
    return f"{x:.6g}"


def render_doc(t: dict) -> str:
    out = [
        "# Drive parameters",
        "",
        "<!-- generated by `fluxdrive params --write` from firmware/app/drive_param_table.h; "
        "do not edit -->",
        "",
        "One table in the firmware (`firmware/app/drive_param_table.h`) defines every drive "
        "parameter: the C struct and its defaults, the range check, CAN access by id "
        "(`PARAM_REQ`, `docs/can.md`), the ISR stream of the PIL replay, the scenario keys "
        "(`docs/scenarios.md`), the DBC value table and the tools' names. This page is "
        "generated from it (`fluxdrive params --write`; the CTest test `params/agreement` "
        "fails when it, the DBC or the tools' table differ from the firmware).",
        "",
        "Access: `ro` read only; `idle` written with the gates off (idle or fault); `live` "
        "also while running. Every write is checked against the range below, then the set as "
        "a whole (relations between fields, e.g. `i_trip >= i_max`, and the law in force "
        "still available on the machine), and applied by the ISR at its next period (the "
        "non-live part of a set waits until the gates are off). Scenario keys outside "
        "`controller` are converted by their section (`inverter.pwm_frequency` sets `ts`).",
        "",
        "| id | name | type | unit | default | min | max | access | scenario key | description |",
        "|---:|---|---|---|---:|---:|---:|---|---|---|",
    ]
    for p in t["params"]:
        enum = p["type"] in ("law", "mode", "pos_source")
        lists = {"law": "laws", "mode": "modes", "pos_source": "pos_sources"}
        if enum:
            names = t[lists[p["type"]]]
            d, lo, hi = names[int(p["default"])], names[0], names[-1]
        elif p["type"] == "map":
            d, lo, hi = "none", "-", "-"
        else:
            d, lo, hi = _num(p["default"]), _num(p["min"]), _num(p["max"])
        out.append(f"| {p['id']} | `{p['name']}` | {p['type']} | {p['unit']} | {d} | {lo} | {hi} "
                   f"| {p['access']} | `{p['scenario']}` | {p['doc']} |")
    out += ["", "CAN protocol parameters (`firmware/app/can_proto.h`):", "",
            "| id | name | access |", "|---:|---|---|"]
    for p in t["can_params"]:
        out.append(f"| {p['id']} | `{p['name']}` | {p['access']} |")
    out += ["", "## Named values", ""]
    for key, title in (("laws", "Control laws"), ("modes", "Modes"), ("states", "States"),
                       ("pos_sources", "Position sources")):
        out.append(f"* {title}: " + ", ".join(f"{i} `{n}`" for i, n in enumerate(t[key])))
    out.append("* Procedures (`CMD_PROC`, `TM_PROC`; * identification, run alone by `CMD_PROC`): "
               + ", ".join(f"{i} `{p['name']}`{' *' if p['ident'] else ''}"
                           for i, p in enumerate(t["procs"])))
    out.append("* Fault bits: " + ", ".join(f"{b} `{n}`" for b, n in enumerate(t["faults"])))
    out.append("* CAN reply results: " + ", ".join(f"{i} `{n}`"
                                                   for i, n in enumerate(t["can_results"])))
    out.append(f"* CMD_STATE `enable`, `mode`, `law`: {t['can_keep']} keeps the setting.")
    out.append("")
    return "\n".join(out)


def render_tables(t: dict) -> str:
    return json.dumps(t, indent=1, sort_keys=True) + "\n"


def targets(root: Path, t: dict) -> dict[Path, str]:
    dbc = root / DBC_REL
    return {
        dbc: render_dbc(dbc.read_text(encoding="utf-8"), t),
        root / DOC_REL: render_doc(t),
        root / TABLES_REL: render_tables(t),
    }


def sync_generated(root: Path, files: dict[Path, str], write: bool) -> list[Path]:
    """The generated files whose text differs from files' (written when
    write): shared by `fluxdrive params` and `fluxdrive signals`."""
    differ = []
    for path, text in files.items():
        old = path.read_text(encoding="utf-8") if path.exists() else None
        if old == text:
            continue
        differ.append(path)
        if write:
            path.write_text(text, encoding="utf-8")
            print(f"wrote {path.relative_to(root)}")
    return differ


def report_differ(root: Path, differ: list[Path], source: str, fix: str) -> None:
    for p in differ:
        print(f"differs from {source}: {p.relative_to(root)}")
    print(f"regenerate with: {fix}")


def main(args: argparse.Namespace) -> int:
    from fluxdrive.sil import find_repo_root, locate_sil

    root = find_repo_root() or Path.cwd()
    t = from_sil(locate_sil(args.sil))
    differ = sync_generated(root, targets(root, t), args.write)
    if args.check and differ:
        report_differ(root, differ, "the firmware's table", "fluxdrive params --write")
        return 1
    if not differ:
        print("DBC, tools table and docs/parameters.md agree with the firmware's table")
    return 0
