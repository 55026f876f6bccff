"""`fluxdrive map ...`: load, validate, convert, tabulate, plot, document.

  check FILE           validate and summarise (FILE: .npz, .csv, .fdmap or preset:NAME)
  convert IN -o OUT    into a .fdmap blob (the SIL runs this at start-up for .npz/.csv)
  ctable IN -o OUT.c   the blob as a C table (board builds)
  generate             the committed preset files (--write / --check)
  plot FILE -o DIR     figures
  doc                  the generated part of docs/flux-maps.md (--write / --check)
Errors: ``fluxdrive map: FILE: CHECK: WHERE: DETAIL`` on stderr, exit 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import FluxMapError

REPO = Path(__file__).resolve().parents[4]


def _load(args, file: str):
    from . import blob, io
    from .model import FluxMap

    if file.endswith(".fdmap"):
        b = blob.read(file)
        return FluxMap(b["i_d"], b["i_q"], b["psi_d"].astype(float), b["psi_q"].astype(float),
                       int(b["pole_pairs"]), Path(file).stem, ["read from a .fdmap blob"])
    return io.load(file, getattr(args, "convention", None), getattr(args, "mirror", False),
                   getattr(args, "pole_pairs", None), getattr(args, "flux_unit", None),
                   getattr(args, "current_unit", None), getattr(args, "i_max", None),
                   getattr(args, "v_dc", None), getattr(args, "speed", None))


def cmd_check(args) -> int:
    from .summary import describe

    m = _load(args, args.file)
    print(describe(m))
    return 0


def cmd_convert(args) -> int:
    from . import blob

    m = _load(args, args.input)
    Path(args.output).write_bytes(blob.to_bytes(m))
    return 0


def cmd_ctable(args) -> int:
    from . import blob

    m = _load(args, args.input)
    Path(args.output).write_text(blob.ctable(blob.to_bytes(m), args.symbol, args.input))
    return 0


def cmd_generate(args) -> int:
    from .files import generate

    return generate(REPO, write=args.write)


def cmd_plot(args) -> int:
    from .plots import plot_all

    m = _load(args, args.file)
    for p in plot_all(m, Path(args.output), getattr(args, "v_dc", None)):
        print(p)
    return 0


def cmd_doc(args) -> int:
    from .doc import render

    return render(REPO, Path(args.file), write=args.write)


def add_parser(sub) -> None:
    p = sub.add_parser("map", help="flux maps of saturated machines (docs/flux-maps.md)")
    ms = p.add_subparsers(dest="map_cmd", required=True)

    def load_opts(q, plot=False):
        q.add_argument("--convention", choices=("fluxdrive", "syr"),
                       help="axis convention of the file (default: the file's, else fluxdrive)")
        q.add_argument("--mirror", action="store_true",
                       help="complete a map of i_q >= 0 (fluxdrive frame) by symmetry")
        q.add_argument("--pole-pairs", type=int,
                       help="pole pairs, for a file without them (a file's own must agree)")
        q.add_argument("--flux-unit", choices=("Vs", "mVs"),
                       help="unit of the file's flux linkages (default: the file's, else Vs)")
        q.add_argument("--current-unit", choices=("A", "mA"),
                       help="unit of the file's currents (default: the file's, else A)")
        q.add_argument("--i-max", type=float, metavar="A",
                       help="the machine's current limit (peak): checks the map's current unit")
        q.add_argument("--speed", type=float, metavar="RPM",
                       help="rated (or top) speed: with --v-dc checks the flux unit")
        if not plot:
            q.add_argument("--v-dc", type=float, metavar="V",
                           help="DC link: with --speed checks the flux unit")

    q = ms.add_parser("check", help="validate and summarise a map")
    q.add_argument("file", metavar="FILE")
    load_opts(q)
    q.set_defaults(func=_guard(cmd_check))
    q = ms.add_parser("convert", help="a map into a .fdmap blob")
    q.add_argument("input", metavar="IN")
    q.add_argument("-o", "--output", required=True, metavar="OUT.fdmap")
    load_opts(q)
    q.set_defaults(func=_guard(cmd_convert))
    q = ms.add_parser("ctable", help="a map as the C table a board build links")
    q.add_argument("input", metavar="IN")
    q.add_argument("-o", "--output", required=True, metavar="OUT.c")
    q.add_argument("--symbol", default="fd_machine_map")
    load_opts(q)
    q.set_defaults(func=_guard(cmd_ctable))
    q = ms.add_parser("generate", help="the committed preset maps (maps/)")
    g = q.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true")
    g.add_argument("--check", action="store_true")
    q.set_defaults(func=_guard(cmd_generate))
    q = ms.add_parser("plot", help="figures of a map")
    q.add_argument("file", metavar="FILE")
    q.add_argument("-o", "--output", required=True, metavar="DIR")
    q.add_argument("--v-dc", type=float, help="DC link for the voltage-limit curves [V]")
    load_opts(q, plot=True)
    q.set_defaults(func=_guard(cmd_plot))
    q = ms.add_parser("doc", help="the generated part of docs/flux-maps.md")
    q.add_argument("--file", default=str(REPO / "docs" / "flux-maps.md"))
    g = q.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true")
    g.add_argument("--check", action="store_true")
    q.set_defaults(func=_guard(cmd_doc))


def _guard(fn):
    def run(args: argparse.Namespace) -> int:
        try:
            return fn(args)
        except FluxMapError as e:
            print(f"fluxdrive map: {e}", file=sys.stderr)
            return 2
    return run
