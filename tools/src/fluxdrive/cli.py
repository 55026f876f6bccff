"""``fluxdrive`` command line: run, plot, summary, bench."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from fluxdrive import __version__
from fluxdrive.errors import EXIT_USAGE, FluxdriveError

PROG = "fluxdrive"


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {value}")
    return value


def _isrs(text: str) -> int:
    """``--isrs``: a count, or ``all`` / 0 for every ISR (returned as 0)."""
    if text.strip().lower() == "all":
        return 0
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of ISRs or 'all', got {text!r}") \
            from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number of ISRs or 'all', got {value}")
    return value


def _percent(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a percentage, got {text!r}") from None
    if not 0.0 < value <= 100.0:
        raise argparse.ArgumentTypeError(f"expected a percentage in (0, 100], got {value}")
    return value


def _existing_file(path: str, what: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise FluxdriveError(f"{what} not found: {p}")
    if not p.is_file():
        raise FluxdriveError(f"{what} is not a file: {p}")
    return p


# --------------------------------------------------------------------- run
def cmd_run(args: argparse.Namespace) -> int:
    from fluxdrive import logs, sil
    from fluxdrive.summary import format_summary, load_summary

    scenario = _existing_file(args.scenario, "scenario")
    groups = logs.parse_groups(args.signals)
    runner = sil.locate_sil(args.sil)

    out_dir = Path(args.out) if args.out else Path("out") / scenario.stem
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FluxdriveError(f"cannot create output directory {out_dir}: {exc}") from None
    log_path = out_dir / "log.npy"
    summary_path = out_dir / "summary.json"
    plot_path = Path(args.plot) if args.plot else out_dir / "plot.png"
    for stale in (log_path, summary_path):  # never report a previous run's output
        stale.unlink(missing_ok=True)

    argv = sil.build_argv(runner, scenario, log_path, summary_path, args.decimate)
    result = sil.run_sil(argv)
    sil.relay_stderr(result)
    if not result.ok:
        print(f"{PROG}: SIL runner failed (exit code {result.returncode})", file=sys.stderr)
        return result.returncode

    if summary_path.is_file():
        summary = load_summary(summary_path)
    else:
        summary = sil.parse_summary_stdout(result.stdout)
        if summary is None:
            raise FluxdriveError(
                "SIL runner wrote no summary file and printed no summary JSON", exit_code=1
            )
        summary_path.write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")

    name = sil.scenario_name(scenario)
    print(format_summary(summary, title=f"scenario: {name}"))
    print()
    print(f"log:     {log_path}")
    print(f"summary: {summary_path}")
    if not args.no_plot:
        from fluxdrive.plotting import plot_log

        if not log_path.is_file():
            raise FluxdriveError(f"SIL runner did not write the log {log_path}", exit_code=1)
        log = logs.load_log(log_path)
        plot_log(log, groups, plot_path, title=name)
        print(f"plot:    {plot_path}")
    return 0


# -------------------------------------------------------------------- plot
def cmd_plot(args: argparse.Namespace) -> int:
    from fluxdrive import logs
    from fluxdrive.plotting import plot_log

    groups = logs.parse_groups(args.signals)
    log = logs.load_log(args.log)
    logs.check_signals(log, groups)
    log = logs.time_window(log, args.t0, args.t1)
    src = Path(args.log)
    out = Path(args.out) if args.out else src.with_suffix(".png")
    title = args.title or (src.parent.name if src.stem == "log" and src.parent.name else src.stem)
    plot_log(log, groups, out, title=title)
    print(f"plot: {out}")
    return 0


# ----------------------------------------------------------------- summary
def cmd_summary(args: argparse.Namespace) -> int:
    from fluxdrive.summary import format_summary, load_summary

    data = load_summary(args.summary)
    if args.json:
        print(json.dumps(data, indent=2, sort_keys=False))
    else:
        print(format_summary(data, title=str(args.summary)))
    return 0


# ------------------------------------------------------------------- bench
def cmd_bench(args: argparse.Namespace) -> int:
    from fluxdrive import bench, sil

    scenario = _existing_file(args.scenario, "scenario")
    runner = sil.locate_sil(args.sil)
    runs: list[bench.BenchRun] = []
    for i in range(1, args.repeat + 1):
        result, run = bench.bench_once(runner, scenario)
        if run is None:
            sil.relay_stderr(result)
            print(f"{PROG}: SIL runner failed (exit code {result.returncode})", file=sys.stderr)
            return result.returncode
        runs.append(run)
        print(bench.format_run(i, run), flush=True)
    print(bench.format_report(bench.BenchReport(runs)))
    return 0


# ------------------------------------------------------------------ parser
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="fluxdrive host tools: run SIL scenarios, plot logs, print summaries, benchmark.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    sig_help = (
        "signals to plot; ',' separates signals in one subplot, ';' separates subplots "
        "(default: speed,speed_ref;torque,torque_ref;i_a,i_b,i_c)"
    )
    sil_help = (
        "path of the fluxdrive-sil binary (default: $FLUXDRIVE_SIL, else "
        "build/host-release/sil/fluxdrive-sil in the repo)"
    )

    p = sub.add_parser("run", help="run a SIL scenario, write log + summary + plot")
    p.add_argument("scenario", metavar="SCENARIO", help="scenario JSON file")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    p.add_argument("--out", metavar="DIR", help="output directory (default: out/<scenario stem>/)")
    p.add_argument("--plot", metavar="PNG", help="plot file (default: <out>/plot.png)")
    p.add_argument("--no-plot", action="store_true", help="do not draw a plot")
    p.add_argument("--signals", metavar="GROUPS", help=sig_help)
    p.add_argument("--decimate", type=_positive_int, metavar="N", help="log every N-th step")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("plot", help="plot signals from a log (.npy)")
    p.add_argument("log", metavar="LOG.npy")
    p.add_argument("--signals", metavar="GROUPS", help=sig_help)
    p.add_argument("--out", metavar="PNG", help="plot file (default: LOG with .png suffix)")
    p.add_argument("--t0", type=float, metavar="S", help="start time [s]")
    p.add_argument("--t1", type=float, metavar="S", help="end time [s]")
    p.add_argument("--title", help="plot title (default: from the log path)")
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser("summary", help="pretty-print a summary JSON")
    p.add_argument("summary", metavar="SUMMARY.json")
    p.add_argument("--json", action="store_true", help="print indented JSON instead of a table")
    p.set_defaults(func=cmd_summary)

    p = sub.add_parser("bench", help="benchmark a scenario (real-time factor)")
    p.add_argument("scenario", metavar="SCENARIO", help="scenario JSON file")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    p.add_argument("--repeat", type=_positive_int, default=3, metavar="N", help="runs (default 3)")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("capability", help="torque/power capability vs speed from the machine model")
    p.add_argument("scenario", metavar="SCENARIO", help="scenario JSON file (machine, limits)")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    p.add_argument("--min-rpm", type=float, default=100.0)
    p.add_argument("--max-rpm", type=float, default=1200.0)
    p.add_argument("--points", type=_positive_int, default=23)
    p.set_defaults(func=_cmd_capability)

    p = sub.add_parser("rubino2020", help="reproduce Rubino 2020 in SIL: figures + results table")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    p.add_argument("--out", metavar="DIR", help="logs (default: out/rubino2020)")
    p.add_argument("--figures", metavar="DIR", help="figures (default: docs/figures)")
    p.add_argument("--doc", metavar="MD", help="markdown file whose results table is replaced")
    p.set_defaults(func=_cmd_rubino)

    p = sub.add_parser("varatharajan2022",
                       help="reproduce Varatharajan 2022 (decoupled DFVC) in SIL: figures + tables")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    p.add_argument("--out", metavar="DIR", help="logs (default: out/varatharajan2022)")
    p.add_argument("--figures", metavar="DIR", help="figures (default: docs/figures)")
    p.add_argument("--doc", metavar="MD", help="markdown file whose results tables are replaced")
    p.set_defaults(func=_cmd_varatharajan)

    p = sub.add_parser("fabbri2022",
                       help="reproduce Fabbri 2022 (DFC + IVD star-point position) in SIL")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    p.add_argument("--out", metavar="DIR", help="logs (default: out/fabbri2022)")
    p.add_argument("--figures", metavar="DIR", help="figures (default: docs/figures)")
    p.add_argument("--doc", metavar="MD", help="markdown file whose results tables are replaced")
    p.add_argument("--shifts", action="store_true",
                   help="only print the Full IVD's two phase shifts identified on plants with "
                        "phi_b = 2, 1/2, 0 times phi_a and a drawn pair (issue 23, point 6)")
    p.add_argument("--noise-sweep", action="store_true",
                   help="only print the Table 5.2 ratio IVD+KF / DFC+KF over the star channel's "
                        "noise (0.005 .. 0.1 V, 3 seeds, 100 and 500 rpm; issue 23, point 7)")
    p.set_defaults(func=_cmd_fabbri)

    p = sub.add_parser("pil", help="PIL: replay a scenario's ISRs on QEMU, compare, count")
    p.add_argument("scenario", nargs="+", metavar="SCENARIO", help="scenario JSON file(s)")
    p.add_argument("--law", metavar="LAWS", help="foc,pi_dfvc,db_dfvc (default: the scenario's)")
    p.add_argument("--isrs", type=_isrs, default=3000, metavar="N|all",
                   help="ISRs traced for the instruction and cycle counts, from the start "
                   "of each run (default 3000; all or 0: the whole run)")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    p.add_argument("--elf", metavar="PATH", help="PIL image (default: $FLUXDRIVE_PIL_ELF, else "
                   "build/cortex-m4f/pil/fluxdrive-pil.elf)")
    p.add_argument("--out", metavar="DIR", help="work directory (default: out/pil)")
    p.add_argument("--markdown", metavar="MD", help="write the report section into MD "
                   "(e.g. docs/benchmarks.md)")
    p.add_argument("--check-worst", type=_positive_int, metavar="N",
                   help="fail when the DB-DFVC worst case reaches N instructions")
    p.add_argument("--check-worst-all", type=_positive_int, metavar="N",
                   help="fail when any run's worst case (every law) reaches N instructions")
    p.add_argument("--check-mean", type=_positive_int, metavar="N",
                   help="fail when a run's mean reaches N instructions per law ISR")
    p.add_argument("--check-mean-cordic", type=_positive_int, metavar="N",
                   help="fail when a run's mean with the core's trigonometry on the board's "
                   "CORDIC co-processor reaches N instructions (needs --board-elf, --functions)")
    p.add_argument("--check-call", action="append", default=[], metavar="FUNC=N",
                   help="fail when FUNC's mean instructions per call (callees included) "
                   "exceed N, or FUNC was not called (repeatable; needs the trace)")
    p.add_argument("--check-cycles", type=_percent, metavar="PCT",
                   help="fail when the DB-DFVC worst case's estimated cycles exceed PCT %% of "
                   "the 10625-cycle budget (170 MHz / 16 kHz)")
    p.add_argument("--check-board", type=_percent, metavar="PCT",
                   help="fail when a run's board worst case (estimated cycles, the core's "
                   "trigonometry on the CORDIC co-processor) exceeds PCT %% of its budget "
                   "(needs --board-elf)")
    p.add_argument("--board-elf", metavar="PATH", help="board image (e.g. build/stm32g474/boards/"
                   "stm32g4/fluxdrive-g474.elf): add the ISR wrapper, exception and board HAL "
                   "(fluxdrive cycles-board) to a board estimate")
    p.add_argument("--cpi", type=float, default=None, help="legacy: also show the worst case at "
                   "this flat cycles/instruction (the report uses the cycle model)")
    p.add_argument("--functions", action="store_true",
                   help="also list the mean instructions and cycles per function")
    p.add_argument("--procs", action="store_true",
                   help="also group the ISRs by the procedure the host's drive had in force "
                   "(offsets, identification ...), each reported and checked like a law; a "
                   "run without law ISRs then reports its procedures only")
    p.add_argument("--sample", type=_positive_int, metavar="W",
                   help="with --procs: trace, in place of the first --isrs ISRs, windows: of "
                   "each procedure's run its first and last W ISRs and W around each change "
                   "of its phase (the replay's state carried into each window through "
                   "pil_snap.bin; every ISR is still replayed and compared)")
    p.add_argument("--proc-limit", action="append", default=[], metavar="PROC=MEAN,WORST,PCT",
                   help="with --procs: check PROC's ISRs against these (mean and worst "
                   "instructions, board worst %% of the budget) in place of --check-mean, "
                   "--check-worst-all and --check-board (repeatable; a guard for a procedure "
                   "not yet within those, docs/pil.md)")
    p.add_argument("--free-running", action="store_true",
                   help="do not force the applied voltage (docs/pil.md)")
    p.add_argument("--timeout", type=float, default=600.0, help="per QEMU run [s]")
    p.set_defaults(func=lambda a: __import__("fluxdrive.pil").pil.main(a))
    p = sub.add_parser("params", help="the drive's parameter table into the DBC, the tools' "
                       "table and docs/parameters.md")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    mx = p.add_mutually_exclusive_group()
    mx.add_argument("--write", action="store_true", help="regenerate the files that differ")
    mx.add_argument("--check", action="store_true", help="exit 1 when a file differs")
    p.set_defaults(func=lambda a: __import__("fluxdrive.params").params.main(a))
    p = sub.add_parser("signals", help="the signal tables into docs/log-format.md, the DBC's "
                       "signal comments and the tools' signal table")
    p.add_argument("--sil", metavar="PATH", help=sil_help)
    mx = p.add_mutually_exclusive_group()
    mx.add_argument("--write", action="store_true", help="regenerate the files that differ")
    mx.add_argument("--check", action="store_true", help="exit 1 when a file differs")
    p.set_defaults(func=lambda a: __import__("fluxdrive.signals").signals.main(a))

    p = sub.add_parser("cycles-board", help="cycle bound of the board's ISR path outside "
                       "drive_isr (wrapper, exception, register HAL)")
    p.add_argument("elf", metavar="ELF", help="board image, e.g. "
                   "build/stm32g474/boards/stm32g4/fluxdrive-g474.elf")
    p.set_defaults(func=lambda a: __import__("fluxdrive.cm4_cycles").cm4_cycles.main_board(a))
    from fluxdrive.can.cli import add_parser as add_can_parser  # fluxdrive can ...
    from fluxdrive.fluxmap.cli import add_parser as add_map_parser  # fluxdrive map ...

    add_map_parser(sub)
    from fluxdrive.machines import add_parser as add_machines_parser  # fluxdrive machines ...

    add_machines_parser(sub)

    add_can_parser(sub)
    from fluxdrive.commission import add_parser as add_commission_parser  # fluxdrive commission

    add_commission_parser(sub)
    return parser


def _cmd_capability(args: argparse.Namespace) -> int:
    from fluxdrive.capability import main_capability

    return main_capability(args)


def _cmd_rubino(args: argparse.Namespace) -> int:
    from fluxdrive.rubino2020 import main_rubino

    return main_rubino(args)


def _cmd_fabbri(args: argparse.Namespace) -> int:
    from fluxdrive.fabbri2022 import main_fabbri

    return main_fabbri(args)


def _cmd_varatharajan(args: argparse.Namespace) -> int:
    from fluxdrive.varatharajan2022 import main_varatharajan

    return main_varatharajan(args)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except FluxdriveError as exc:
        print(f"{PROG}: error: {exc.message}", file=sys.stderr)
        if exc.hint:
            print(f"{PROG}: hint: {exc.hint}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `fluxdrive summary x.json | head`
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
