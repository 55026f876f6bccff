"""Map files into a validated FluxMap (fluxdrive frame).

NPZ: either 1-D ``i_d``, ``i_q`` and 2-D ``psi_d``, ``psi_q`` of shape
(len(i_q), len(i_d)) (row = i_q index), or complex 2-D ``i_s_dq``,
``psi_s_dq`` (i_d + j i_q, psi_d + j psi_q, as measured-map archives store
them) on a grid in either orientation: rows holding one i_q (columns one
i_d), or rows holding one i_d (columns one i_q, motulator's published
layout), the orientation found reported in FluxMap.notes. Optional
scalars: ``pole_pairs``, ``convention`` ("fluxdrive" or "syr"),
``flux_unit`` ("Vs", "mVs"), ``current_unit`` ("A", "mA").

CSV, long form: a header ``i_d,i_q,psi_d,psi_q`` and one operating point a
line, in any order, forming a complete regular grid; optional comment
lines before the header: ``# pole_pairs=2``, ``# convention=syr``,
``# flux_unit=mVs``, ``# current_unit=mA``.

Units: A and Vs (peak, per phase, amplitude-invariant dq) unless stated.
The convention stated is checked against the data (validate.
detect_convention: the PM flux at zero current, the saliency), and taken
from the data when none is stated; "syr" (d on the maximum inductance, PM
on -q) is turned into fluxdrive's at load (model.syr_to_fluxdrive).
``mirror``: a map given for i_q >= 0 only (fluxdrive frame) is completed by
the machine's symmetry lambda_d(i_d, -i_q) = lambda_d(i_d, i_q),
lambda_q(i_d, -i_q) = -lambda_q(i_d, i_q); reported in FluxMap.notes.
"""

from __future__ import annotations

import csv
import io as _io
import zipfile
from pathlib import Path

import numpy as np

from .errors import FluxMapError
from .model import FluxMap, syr_to_fluxdrive
from .validate import (check_axis, check_convention, check_map, check_tables, check_units,
                       detect_convention)

CONVENTIONS = ("fluxdrive", "syr")
FLUX_UNITS = {"Vs": 1.0, "mVs": 1e-3}
CURRENT_UNITS = {"A": 1.0, "mA": 1e-3}
META = ("pole_pairs", "convention", "flux_unit", "current_unit")


def _scalar(file, z, key):
    if key not in z.files:
        return None
    a = z[key]
    if a.shape != ():
        raise FluxMapError(file, f"{key} not a scalar", f"shape {a.shape}")
    return a.item()


def _from_complex(file: str, i_s, psi_s):
    """The grid of complex arrays in either orientation: rows holding one
    i_q (columns one i_d), or rows holding one i_d (columns one i_q, as
    motulator publishes its measured maps), read transposed. Returns the
    arrays and the orientation found."""
    if i_s.ndim != 2 or psi_s.ndim != 2:
        raise FluxMapError(file, "wrong shape", f"i_s_dq {i_s.shape}, psi_s_dq {psi_s.shape}: "
                           "2-D complex arrays expected")
    if i_s.shape != psi_s.shape:
        raise FluxMapError(file, "wrong shape", f"i_s_dq {i_s.shape} and psi_s_dq "
                           f"{psi_s.shape} differ")
    if not (np.iscomplexobj(i_s) and np.iscomplexobj(psi_s)):
        raise FluxMapError(file, "not complex", "i_s_dq and psi_s_dq must be complex (d + j q)")

    def grid(c):
        # rows holding one i_q, columns one i_d
        i_d, i_q = c.real[0, :], c.imag[:, 0]
        return (np.allclose(c.real, i_d[None, :], rtol=0, atol=1e-9 * (1 + np.abs(i_d).max()))
                and np.allclose(c.imag, i_q[:, None], rtol=0,
                                atol=1e-9 * (1 + np.abs(i_q).max())))

    n0, n1 = i_s.shape
    if grid(i_s):
        return (i_s.real[0, :], i_s.imag[:, 0], psi_s.real, psi_s.imag,
                f"complex arrays {n0} x {n1}, rows hold one i_q, columns one i_d")
    if grid(i_s.T):
        return (i_s.real[:, 0], i_s.imag[0, :], psi_s.real.T, psi_s.imag.T,
                f"complex arrays {n0} x {n1}, rows hold one i_d, columns one i_q (read "
                "transposed)")
    raise FluxMapError(file, "irregular grid", "i_s_dq is not a grid in either orientation (rows "
                       "holding one i_q and columns one i_d, or rows holding one i_d and columns "
                       "one i_q)")


def _load_npz(file: str):
    try:
        with np.load(file, allow_pickle=False) as z:
            keys = set(z.files)
            if {"i_s_dq", "psi_s_dq"} <= keys:
                *arrays, layout = _from_complex(file, z["i_s_dq"], z["psi_s_dq"])
            elif {"i_d", "i_q", "psi_d", "psi_q"} <= keys:
                arrays = [np.asarray(z[k]) for k in ("i_d", "i_q", "psi_d", "psi_q")]
                layout = "real arrays i_d, i_q, psi_d, psi_q (rows: i_q)"
            else:
                raise FluxMapError(file, "missing arrays", f"has {sorted(keys)}; needs i_d, i_q, "
                                   "psi_d, psi_q or i_s_dq, psi_s_dq")
            meta = {k: _scalar(file, z, k) for k in META}
    except FluxMapError:
        raise
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as e:
        raise FluxMapError(file, "not an NPZ archive", str(e).splitlines()[0]) from None
    return arrays, meta, layout


def _load_csv(file: str):
    text = Path(file).read_text(errors="replace")
    meta: dict[str, str] = {}
    lines = text.splitlines()
    body = []
    for n, line in enumerate(lines, 1):
        s = line.strip()
        if s.startswith("#"):
            if "=" in s:
                k, v = s[1:].split("=", 1)
                meta[k.strip()] = v.strip()
            continue
        if s:
            body.append((n, s))
    if not body:
        raise FluxMapError(file, "empty file", "no header and no operating point")
    n0, header = body[0]
    cols = [c.strip() for c in header.split(",")]
    if cols != ["i_d", "i_q", "psi_d", "psi_q"]:
        raise FluxMapError(file, "bad header", f"line {n0}: {header!r}, expected "
                           "'i_d,i_q,psi_d,psi_q'")
    rows = []
    for n, s in body[1:]:
        parts = next(csv.reader(_io.StringIO(s)))
        if len(parts) != 4:
            raise FluxMapError(file, "wrong number of columns", f"line {n}",
                               f"{len(parts)} values, 4 expected")
        try:
            rows.append((n, *(float(p) for p in parts)))
        except ValueError:
            raise FluxMapError(file, "not a number", f"line {n}", repr(s)) from None
    if not rows:
        raise FluxMapError(file, "empty file", "a header and no operating point")
    a = np.array([r[1:] for r in rows])
    i_d, i_q = np.unique(a[:, 0]), np.unique(a[:, 1])
    check_axis(file, "i_d", i_d)
    check_axis(file, "i_q", i_q)
    psi_d = np.full((len(i_q), len(i_d)), np.nan)
    psi_q = np.full_like(psi_d, np.nan)
    seen = np.zeros(psi_d.shape, bool)
    for (n, d, q, pd, pq) in rows:
        j, k = int(np.searchsorted(i_d, d)), int(np.searchsorted(i_q, q))
        if seen[k, j]:
            raise FluxMapError(file, "duplicate operating point", f"line {n}",
                               f"i_d = {d:g}, i_q = {q:g} given twice")
        seen[k, j] = True
        psi_d[k, j], psi_q[k, j] = pd, pq
    if not seen.all():
        k, j = (int(x[0]) for x in np.nonzero(~seen))
        raise FluxMapError(file, "missing operating point",
                           f"i_d = {i_d[j]:g} A, i_q = {i_q[k]:g} A",
                           f"{int((~seen).sum())} grid point(s) missing in all")
    pp = meta.get("pole_pairs")
    try:
        pp = int(pp) if pp is not None else None
    except ValueError:
        raise FluxMapError(file, "pole pairs", f"'# pole_pairs={pp}': not an integer") from None
    return ((i_d, i_q, psi_d, psi_q), {**{k: meta.get(k) for k in META}, "pole_pairs": pp},
            "long-form CSV")


def mirror_iq(file: str, i_d, i_q, psi_d, psi_q):
    """Completes a map of i_q >= 0 (fluxdrive frame) by symmetry."""
    if not np.isclose(i_q[0], 0.0, atol=1e-9 * (1 + abs(i_q[-1]))):
        raise FluxMapError(file, "cannot mirror", f"i_q starts at {i_q[0]:g} A; --mirror needs a "
                           "map of i_q >= 0 starting at 0")
    iq = np.concatenate([-i_q[:0:-1], i_q])
    pd = np.concatenate([psi_d[:0:-1, :], psi_d], axis=0)
    pq = np.concatenate([-psi_q[:0:-1, :], psi_q], axis=0)
    return i_d, iq + 0.0, pd, pq


def _unit(file, what, given, table):
    if given not in table:
        raise FluxMapError(file, f"unknown {what} unit", f"{given!r}: {', '.join(table)}")
    return table[given]


def load(path: str | Path, convention: str | None = None, mirror: bool = False,
         pole_pairs: int | None = None, flux_unit: str | None = None,
         current_unit: str | None = None, i_max: float | None = None,
         v_dc: float | None = None, speed_rpm: float | None = None) -> FluxMap:
    """A map file (.npz, .csv) or ``preset:NAME`` into a validated FluxMap.

    The convention stated (option, else the file's) is checked against the
    one the data show (validate.detect_convention); with none stated the
    detected one is taken. Units (option, else the file's, else Vs and A)
    scale the arrays; the result is checked for plausibility
    (validate.check_units, with i_max [A], v_dc [V] and speed_rpm where
    known) and its tables for the map's range (validate.check_tables)."""
    file = str(path)
    if file.startswith("preset:"):
        from .presets import preset_map
        return preset_map(file[7:])
    p = Path(file)
    if not p.is_file():
        raise FluxMapError(file, "cannot open", "no such file")
    if p.suffix == ".npz":
        arrays, meta, layout = _load_npz(file)
    elif p.suffix == ".csv":
        arrays, meta, layout = _load_csv(file)
    else:
        raise FluxMapError(file, "unknown format", f"'{p.suffix}': .npz or .csv")
    i_d, i_q, psi_d, psi_q = (np.asarray(x, float) for x in arrays)
    notes = [f"layout: {layout}"]
    fu = flux_unit or meta.get("flux_unit") or "Vs"
    cu = current_unit or meta.get("current_unit") or "A"
    kf, kc = _unit(file, "flux", fu, FLUX_UNITS), _unit(file, "current", cu, CURRENT_UNITS)
    if kf != 1.0 or kc != 1.0:
        psi_d, psi_q, i_d, i_q = psi_d * kf, psi_q * kf, i_d * kc, i_q * kc
        notes.append(f"units: flux in {fu}, currents in {cu}, scaled to Vs and A")
    stated = convention or meta.get("convention")
    if stated is not None and stated not in CONVENTIONS:
        raise FluxMapError(file, "unknown convention", f"{stated!r}: {', '.join(CONVENTIONS)}")
    check_axis(file, "i_d", i_d)
    check_axis(file, "i_q", i_q)
    for name, a in (("psi_d", psi_d), ("psi_q", psi_q)):
        if a.shape != (len(i_q), len(i_d)):
            hint = (" (transposed? rows must hold one i_q)"
                    if a.shape == (len(i_d), len(i_q)) else "")
            raise FluxMapError(file, "wrong shape", f"{name} has shape {a.shape}, the axes give "
                               f"({len(i_q)}, {len(i_d)}) (rows: i_q){hint}")
    found = detect_convention(i_d, i_q, psi_d, psi_q)
    conv = check_convention(file, stated, found)
    notes.append(f"convention: {conv}"
                 + (" (stated" if stated else " (not stated: detected")
                 + (f"; the data show {found.evidence})" if found.evidence else
                    "; not detectable: no PM flux and no saliency at zero current)"))
    if conv == "syr":
        i_d, i_q, psi_d, psi_q = syr_to_fluxdrive(i_d, i_q, psi_d, psi_q)
        notes.append("converted from the SyR convention (d on the maximum inductance, PM on -q)")
    if mirror:
        i_d, i_q, psi_d, psi_q = mirror_iq(file, i_d, i_q, psi_d, psi_q)
        notes.append("mirrored to i_q < 0 by symmetry (--mirror)")
    pp = meta.get("pole_pairs")
    if pole_pairs is not None and pp is not None and float(pp) != float(pole_pairs):
        # the file's own count against the one given (--pole-pairs, a
        # scenario's machine.pole_pairs): neither wins silently
        raise FluxMapError(file, "pole pairs", f"the file has {pp:g}, {pole_pairs} given "
                           "(--pole-pairs or a scenario's machine.pole_pairs)")
    pp = pole_pairs if pole_pairs is not None else pp
    if pp is None:
        raise FluxMapError(file, "pole pairs", "not in the file: give --pole-pairs (a scenario: "
                           "machine.pole_pairs)")
    m = FluxMap(i_d, i_q, psi_d, psi_q, int(pp) if float(pp).is_integer() else pp, p.stem, notes)
    check_map(file, m)
    check_units(file, m, i_max=i_max, v_dc=v_dc, speed_rpm=speed_rpm)
    check_tables(file, m)
    return m
