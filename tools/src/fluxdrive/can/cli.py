"""``fluxdrive can ...``: monitor, record, plot, send, doc."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from fluxdrive.errors import FluxdriveError


def add_bus_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--interface", default="socketcand",
                   help="python-can interface: socketcand (default), socketcan, virtual, ...")
    p.add_argument("--channel", default="vcan0", help="bus / interface name (default vcan0)")
    p.add_argument("--host", default="127.0.0.1", help="socketcand host (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=29536, help="socketcand port (default 29536)")
    p.add_argument("--node", type=int, default=1, help="drive node id 0..15 (default 1)")


def _bus(args: argparse.Namespace):
    from fluxdrive.can.drive import open_bus

    try:
        return open_bus(args.channel, args.interface, args.host, args.port)
    except Exception as exc:  # python-can raises many kinds
        raise FluxdriveError(f"cannot open the CAN bus ({args.interface} {args.channel}): {exc}") from None


def _frames(bus, duration: float | None, count: int | None):
    t_end = None if duration is None else time.monotonic() + duration
    n = 0
    while (t_end is None or time.monotonic() < t_end) and (count is None or n < count):
        msg = bus.recv(timeout=0.1)
        if msg is not None:
            n += 1
            yield msg


def cmd_monitor(args: argparse.Namespace) -> int:
    from fluxdrive.can.protocol import Protocol

    proto = Protocol(args.node)
    bus = _bus(args)
    last: dict[str, dict] = {}
    t_print = 0.0
    try:
        for msg in _frames(bus, args.duration, args.count):
            d = proto.decode(msg)
            if d is None:
                continue
            name, sigs = d
            if args.raw:
                vals = " ".join(f"{k}={v:.6g}" for k, v in sigs.items())
                print(f"{msg.timestamp:12.6f} {name:<11} {vals}", flush=True)
                continue
            if name == "REPLY":
                r = proto.reply(msg)
                print(f"{msg.timestamp:12.6f} REPLY {r.req} {r.result} signal={r.signal} "
                      f"param={r.param} value={r.value:.6g}", flush=True)
            last[name] = sigs
            now = time.monotonic()
            if now - t_print >= args.interval:
                t_print = now
                print(f"--- t = {msg.timestamp:.3f} s")
                for mname in sorted(last):
                    print(f"  {mname:<10} " + " ".join(f"{k}={v:.6g}" for k, v in last[mname].items()))
                sys.stdout.flush()
    finally:
        bus.shutdown()
    return 0


def cmd_record(args: argparse.Namespace) -> int:
    import can

    bus = _bus(args)
    n = 0
    try:
        with can.Logger(args.file) as logger:  # format from the suffix: .asc, .log (candump), .blf, .csv
            for msg in _frames(bus, args.duration, args.count):
                logger(msg)
                n += 1
    finally:
        bus.shutdown()
    print(f"recorded {n} frames to {args.file}")
    return 0


def collect(frames, proto, signals: list[str]) -> dict[str, list[tuple[float, float]]]:
    series: dict[str, list[tuple[float, float]]] = {s: [] for s in signals}
    for msg in frames:
        d = proto.decode(msg)
        if d is None:
            continue
        for k, v in d[1].items():
            if k in series:
                series[k].append((float(msg.timestamp), float(v)))
    return series


def plot_series(series: dict, groups: list[list[str]], out: Path, title: str) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 2.6 * len(groups)), dpi=100)
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0]
    for ax, group in zip(axes, groups):
        for s in group:
            pts = series.get(s, [])
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], label=s)
        ax.legend(loc="best", fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("t [s] (frame timestamps)")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(out)


def cmd_plot(args: argparse.Namespace) -> int:
    import can

    from fluxdrive.can.protocol import Protocol

    proto = Protocol(args.node)
    groups = [[s.strip() for s in g.split(",") if s.strip()] for g in args.signals.split(";") if g.strip()]
    known = {s.name for m in proto.db.messages for s in m.signals}
    unknown = [s for g in groups for s in g if s not in known]
    if unknown:
        raise FluxdriveError(f"unknown signal(s): {', '.join(unknown)}", hint="see docs/can.md")
    signals = [s for g in groups for s in g]
    out = Path(args.out)
    if args.recording:
        src = Path(args.recording)
        if not src.is_file():
            raise FluxdriveError(f"recording not found: {src}")
        series = collect(can.LogReader(str(src)), proto, signals)
        title = src.name
    else:
        bus = _bus(args)
        series = {s: [] for s in signals}
        t_end = time.monotonic() + args.duration
        t_draw = time.monotonic()
        try:
            while time.monotonic() < t_end:
                part = collect(_frames(bus, min(args.update, t_end - time.monotonic()), None), proto, signals)
                for k, v in part.items():
                    series[k].extend(v)
                if time.monotonic() - t_draw >= args.update:  # live: the PNG is redrawn
                    plot_series(series, groups, out, f"node {args.node} (live)")
                    t_draw = time.monotonic()
        finally:
            bus.shutdown()
        title = f"node {args.node}"
    if not any(series.values()):
        raise FluxdriveError("no frames with the requested signals", exit_code=1)
    plot_series(series, groups, out, title)
    print(f"plot: {out}")
    return 0


def cmd_send(args: argparse.Namespace) -> int:
    from fluxdrive.can.drive import LAWS, MODES, Drive

    bus = _bus(args)
    drv = Drive(bus=bus, node=args.node, reply_timeout=args.timeout)
    what, vals = args.what, args.values
    try:
        def need(n: int) -> list[str]:
            if len(vals) != n:
                raise FluxdriveError(f"send {what}: expected {n} value(s), got {len(vals)}")
            return vals

        if what == "enable":
            r = drv.enable()
        elif what == "disable":
            r = drv.disable()
        elif what == "clear":
            r = drv.clear_fault()
        elif what == "mode":
            (m,) = need(1)
            if m not in MODES:
                raise FluxdriveError(f"mode must be one of {', '.join(MODES)}")
            r = drv.set_mode(m)
        elif what == "law":
            (m,) = need(1)
            if m not in LAWS:
                raise FluxdriveError(f"law must be one of {', '.join(LAWS)}")
            r = drv.set_law(m)
        elif what == "torque":
            r = drv.set_torque(float(need(1)[0]))
        elif what == "speed":
            r = drv.set_speed(float(need(1)[0]))
        elif what == "current":
            a, b = need(2)
            r = drv.set_current(float(a), float(b))
        elif what == "flux":
            r = drv.set_flux(float(need(1)[0]))
        elif what == "get":
            (p,) = need(1)
            print(f"{p} = {drv.get_param(p):.7g}")
            return 0
        elif what == "set":
            p, v = need(2)
            print(f"{p} = {drv.set_param(p, float(v)):.7g} (acknowledged)")
            return 0
        elif what == "identify":
            (name,) = need(1)
            r = drv.identify(name)  # "stop" stops the one running
        elif what == "heartbeat":
            drv.bus.send(drv.proto.encode("HOST_HB", host_hb_count=0))
            print("heartbeat sent")
            return 0
        else:  # pragma: no cover - argparse choices
            raise FluxdriveError(f"unknown command {what}")
        print(f"{r.req}: {r.result} (value in force {r.value:.7g})")
        return 0
    except ValueError as exc:
        raise FluxdriveError(f"send {what}: {exc}") from None
    finally:
        drv.close()
        bus.shutdown()


def cmd_doc(args: argparse.Namespace) -> int:
    from fluxdrive.can.protocol import message_table_markdown

    print(message_table_markdown(), end="")
    return 0


SEND_HELP = ("enable | disable | clear | mode torque|speed|current | law foc|pi_dfvc|db_dfvc | "
             "torque NM | speed RPM | current ID IQ | flux VS | get PARAM | set PARAM VALUE | "
             "identify PROC|stop | heartbeat")


def add_parser(sub: argparse._SubParsersAction) -> None:
    can_p = sub.add_parser("can", help="talk to a drive over CAN (monitor, record, plot, send, doc)")
    csub = can_p.add_subparsers(dest="can_command", required=True, metavar="CANCOMMAND")

    p = csub.add_parser("monitor", help="decode and print live values")
    add_bus_args(p)
    p.add_argument("--duration", type=float, help="stop after S seconds")
    p.add_argument("--count", type=int, help="stop after N frames")
    p.add_argument("--interval", type=float, default=0.5, help="table refresh [s] (default 0.5)")
    p.add_argument("--raw", action="store_true", help="print every decoded frame")
    p.set_defaults(func=cmd_monitor)

    p = csub.add_parser("record", help="log frames (.asc, .log = candump, .blf, .csv)")
    add_bus_args(p)
    p.add_argument("file", metavar="FILE")
    p.add_argument("--duration", type=float, help="stop after S seconds")
    p.add_argument("--count", type=int, help="stop after N frames")
    p.set_defaults(func=cmd_record)

    p = csub.add_parser("plot", help="plot signals live (PNG redrawn) or from a recording")
    add_bus_args(p)
    p.add_argument("recording", nargs="?", help="a recording (.asc, .log, .blf, .csv); none: live")
    p.add_argument("--signals", default="speed_rpm,speed_ref_rpm;torque_est,torque_ref;i_a,i_b,i_c",
                   help="',' signals in one subplot, ';' subplots")
    p.add_argument("--out", default="can_plot.png", help="PNG (default can_plot.png)")
    p.add_argument("--duration", type=float, default=10.0, help="live: capture S seconds (default 10)")
    p.add_argument("--update", type=float, default=1.0, help="live: redraw every S seconds (default 1)")
    p.set_defaults(func=cmd_plot)

    p = csub.add_parser("send", help="command or parameter write, acknowledge checked")
    add_bus_args(p)
    p.add_argument("what", choices=["enable", "disable", "clear", "mode", "law", "torque", "speed",
                                    "current", "flux", "get", "set", "identify", "heartbeat"], help=SEND_HELP)
    p.add_argument("values", nargs="*")
    p.add_argument("--timeout", type=float, default=1.0, help="reply timeout [s] (default 1)")
    p.set_defaults(func=cmd_send)

    p = csub.add_parser("doc", help="print the message tables of the DBC (Markdown)")
    p.set_defaults(func=cmd_doc)
