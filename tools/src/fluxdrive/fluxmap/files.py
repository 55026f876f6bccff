"""The committed preset files (maps/), regenerated or checked:

* maps/syr_1k1.fdmap, maps/ipm_sat.fdmap: the analytic presets' blobs;
* maps/pmasyr_file.npz (complex i_s_dq, psi_s_dq, SyR convention, with
  pole_pairs and convention) and maps/pmasyr_file.csv (long form, the same
  points): the map-file preset, read through the file path.
--check compares the blobs and the CSV byte for byte and the NPZ's arrays
(an NPZ archive stores its write time)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from . import blob
from .presets import grid_syr, preset_map

BLOBS = ("syr_1k1", "ipm_sat")
FILE_PRESET = "pmasyr"


def _npz_arrays(name: str) -> dict:
    i_d, i_q, pd, pq = grid_syr(name)
    D, Q = np.meshgrid(i_d, i_q)
    return {"i_s_dq": D + 1j * Q, "psi_s_dq": pd + 1j * pq, "pole_pairs": np.array(2),
            "convention": np.array("syr")}


def _csv_text(name: str) -> str:
    i_d, i_q, pd, pq = grid_syr(name)
    out = io.StringIO()
    out.write(f"# {name}: PM-assisted SyR (analytic, fluxdrive map generate), SyR convention\n")
    out.write("# pole_pairs=2\n# convention=syr\ni_d,i_q,psi_d,psi_q\n")
    for k in range(len(i_q)):
        for j in range(len(i_d)):
            out.write(f"{i_d[j]:.6g},{i_q[k]:.6g},{pd[k, j]:.9g},{pq[k, j]:.9g}\n")
    return out.getvalue()


def generate(repo: Path, write: bool) -> int:
    d = repo / "maps"
    d.mkdir(exist_ok=True)
    want: dict[Path, bytes] = {d / f"{n}.fdmap": blob.to_bytes(preset_map(n)) for n in BLOBS}
    want[d / "pmasyr_file.csv"] = _csv_text(FILE_PRESET).encode()
    bad = []
    for p, b in want.items():
        if not (p.is_file() and p.read_bytes() == b):
            bad.append(p)
            if write:
                p.write_bytes(b)
    npz = d / "pmasyr_file.npz"
    arrays = _npz_arrays(FILE_PRESET)
    same = npz.is_file()
    if same:
        with np.load(npz) as z:
            same = set(z.files) == set(arrays) and all(
                np.array_equal(z[k], v) for k, v in arrays.items())
    if not same:
        bad.append(npz)
        if write:
            np.savez(npz, **arrays)
    for p in bad:
        print(f"{'wrote' if write else 'differs'}: {p.relative_to(repo)}")
    return 0 if (write or not bad) else 1
