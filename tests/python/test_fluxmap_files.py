"""Map files refused on load, each kind with its own message naming the
file, the check and (where there is one) the grid cell; and the same map
given as NPZ (real arrays), NPZ (complex arrays), CSV, in either
convention, giving identical blobs."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from fluxdrive.fluxmap import FluxMapError, blob, io
from fluxdrive.fluxmap.model import fluxdrive_to_syr
from fluxdrive.fluxmap.presets import preset_map

REPO = Path(__file__).resolve().parents[2]


def small():
    """A reciprocal analytic map (fluxdrive frame), 9 x 9, both signs of i_q."""
    a = np.linspace(-4.0, 4.0, 9)
    D, Q = np.meshgrid(a, a)
    g = 1.0 / (1.0 + 0.003 * D ** 2)
    pd = 0.1 + 0.1 * D - 0.4 * 9 * np.log(np.cosh(Q / 3)) * 0.006 * D * g * g
    pq = 0.4 * 3 * np.tanh(Q / 3) * g
    return a, a.copy(), pd, pq


def npz(tmp, name, **arrays):
    p = tmp / name
    np.savez(p, **arrays)
    return p


def csv(tmp, name, text):
    p = tmp / name
    p.write_text(text)
    return p


def csv_of(i_d, i_q, pd, pq, head="# pole_pairs=2\n"):
    rows = [f"{i_d[j]},{i_q[k]},{pd[k, j]!r},{pq[k, j]!r}" for k in range(len(i_q))
            for j in range(len(i_d))]
    return head + "i_d,i_q,psi_d,psi_q\n" + "\n".join(rows) + "\n"


def refused(path, check, where=None, **kw):
    with pytest.raises(FluxMapError) as e:
        io.load(path, **kw)
    msg = str(e.value)
    assert str(path) in msg and check in msg, msg
    if where:
        assert where in msg, msg
    return msg


def test_good_map_loads(tmp_path):
    i_d, i_q, pd, pq = small()
    m = io.load(npz(tmp_path, "ok.npz", i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq, pole_pairs=2))
    assert m.nd == 9 and m.pole_pairs == 2 and m.pm_flux() == pytest.approx(0.1)


def test_bad_files(tmp_path):
    i_d, i_q, pd, pq = small()
    ok = dict(i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq, pole_pairs=2)
    kinds = set()

    def bad(path, check, where=None, **kw):
        refused(path, check, where, **kw)
        kinds.add(check)

    bad(tmp_path / "none.npz", "cannot open")
    bad(csv(tmp_path, "m.txt", "x"), "unknown format")
    bad(csv(tmp_path, "junk.npz", "not a zip"), "not an NPZ archive")
    bad(npz(tmp_path, "miss.npz", i_d=i_d, i_q=i_q, psi_d=pd), "missing arrays")
    bad(npz(tmp_path, "shape.npz", **{**ok, "psi_q": pq[:, :-1]}), "wrong shape")
    bad(npz(tmp_path, "axis2d.npz", **{**ok, "i_d": np.vstack([i_d, i_d])}), "axis not 1-D")
    bad(npz(tmp_path, "mono.npz", **{**ok, "i_d": i_d[::-1].copy()}), "axis not increasing",
        "i_d[0]")
    irr = i_d.copy()
    irr[4] += 0.1
    bad(npz(tmp_path, "irr.npz", **{**ok, "i_d": irr}), "irregular grid", "i_d step")
    nan = pd.copy()
    nan[3, 5] = np.nan
    bad(npz(tmp_path, "nan.npz", **{**ok, "psi_d": nan}), "flux not finite",
        "point (5, 3) at i_d = 1 A, i_q = -1 A")
    bad(npz(tmp_path, "one.npz", **{**ok, "i_d": i_d[:1], "psi_d": pd[:, :1],
                                     "psi_q": pq[:, :1]}), "too few points")
    big = np.linspace(-4, 4, 65)
    bad(npz(tmp_path, "big.npz", i_d=big, i_q=i_q, psi_d=np.zeros((9, 65)),
            psi_q=np.zeros((9, 65)), pole_pairs=2), "grid too large")
    neg = pd.copy()
    neg[:, 6] = neg[:, 5] - 0.01  # lambda_d falls from column 5 to 6
    bad(npz(tmp_path, "neg.npz", **{**ok, "psi_d": neg}), "incremental self-inductance not "
        "positive", "cell (5, 0)")
    cross = pd + 2.0 * np.maximum(0.0, i_q[:, None] - 1.0)  # one-way d/dq term beyond 1 A
    bad(npz(tmp_path, "pd.npz", **{**ok, "psi_d": cross}), "not positive definite", "cell (0, 5)")
    weak = pd + 0.02 * np.maximum(0.0, i_q[:, None] - 1.0)  # small one-way term: PD, not reciprocal
    bad(npz(tmp_path, "rec.npz", **{**ok, "psi_d": weak}), "not reciprocal", "cell (0, 5)")
    bad(npz(tmp_path, "half.npz", **{**ok, "i_q": i_q[4:], "psi_d": pd[4:], "psi_q": pq[4:]}),
        "i_q does not cover both signs")
    bad(npz(tmp_path, "nopp.npz", i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq), "pole pairs")
    bad(npz(tmp_path, "conv.npz", **ok, convention="dq0"), "unknown convention")
    c = np.meshgrid(i_d, i_q)
    bad(npz(tmp_path, "cshape.npz", i_s_dq=c[0] + 1j * c[1], psi_s_dq=(pd + 1j * pq)[:, :-1],
            pole_pairs=2), "wrong shape")
    skew = c[0] + 1j * c[1]
    skew[2, 3] += 0.05
    bad(npz(tmp_path, "cgrid.npz", i_s_dq=skew, psi_s_dq=pd + 1j * pq, pole_pairs=2),
        "irregular grid")
    bad(npz(tmp_path, "creal.npz", i_s_dq=c[0], psi_s_dq=pd, pole_pairs=2), "not complex")
    bad(csv(tmp_path, "empty.csv", ""), "empty file")
    bad(csv(tmp_path, "head.csv", "id,iq,psid,psiq\n1,2,3,4\n"), "bad header", "line 1")
    text = csv_of(i_d, i_q, pd, pq)
    lines = text.splitlines()
    bad(csv(tmp_path, "nan.csv", "\n".join(lines[:5] + ["1,2,x,4"] + lines[6:])),
        "not a number", "line 6")
    bad(csv(tmp_path, "cols.csv", "\n".join(lines[:5] + ["1,2,3"] + lines[6:])),
        "wrong number of columns", "line 6")
    bad(csv(tmp_path, "dup.csv", "\n".join(lines + [lines[7]])), "duplicate operating point")
    bad(csv(tmp_path, "hole.csv", "\n".join(lines[:7] + lines[8:])), "missing operating point",
        "i_d = 1 A, i_q = -4 A")
    bad(csv(tmp_path, "mir.csv", csv_of(i_d, i_q, pd, pq)), "cannot mirror", mirror=True)
    print(f"{len(kinds)} kinds of bad map file refused")
    assert len(kinds) >= 15


def test_same_map_every_way(tmp_path):
    """NPZ real / complex, CSV, fluxdrive / SyR convention, half map + mirror:
    one blob."""
    i_d, i_q, pd, pq = small()
    ref = blob.to_bytes(io.load(npz(tmp_path, "a.npz", i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq,
                                    pole_pairs=2)))
    c = np.meshgrid(i_d, i_q)
    b = io.load(npz(tmp_path, "b.npz", i_s_dq=c[0] + 1j * c[1], psi_s_dq=pd + 1j * pq,
                    pole_pairs=2))
    assert blob.to_bytes(b) == ref
    assert blob.to_bytes(io.load(csv(tmp_path, "c.csv", csv_of(i_d, i_q, pd, pq)))) == ref
    sd, sq, spd, spq = fluxdrive_to_syr(i_d, i_q, pd, pq)
    s = io.load(npz(tmp_path, "s.npz", i_d=sd, i_q=sq, psi_d=spd, psi_q=spq, pole_pairs=2),
                convention="syr")
    assert blob.to_bytes(s) == ref
    s2 = io.load(csv(tmp_path, "s.csv", csv_of(sd, sq, spd, spq, "# pole_pairs=2\n"
                                               "# convention=syr\n")))
    assert blob.to_bytes(s2) == ref
    # the SyR map with no convention stated: detected from the data (PM on -q)
    found = io.load(npz(tmp_path, "s2.npz", i_d=sd, i_q=sq, psi_d=spd, psi_q=spq, pole_pairs=2))
    assert blob.to_bytes(found) == ref
    assert any(n.startswith("convention: syr (not stated: detected") for n in found.notes)
    half = io.load(npz(tmp_path, "h.npz", i_d=i_d, i_q=i_q[4:], psi_d=pd[4:], psi_q=pq[4:],
                       pole_pairs=2), mirror=True)
    assert any("mirrored" in n for n in half.notes)
    assert np.allclose(half.psi_q, pq) and np.allclose(half.psi_d, pd)


def test_blob_round_trip_and_crc(tmp_path):
    m = preset_map("syr_1k1")
    b = blob.to_bytes(m)
    assert len(b) == blob.size_bytes(33, 33, 64)
    p = tmp_path / "m.fdmap"
    p.write_bytes(b)
    r = blob.read(p)
    assert r["crc"] == zlib.crc32(b[:-4])
    assert np.array_equal(r["psi_d"], m.psi_d.astype("<f4"))
    bad = bytearray(b)
    bad[200] ^= 1
    p.write_bytes(bytes(bad))
    with pytest.raises(FluxMapError, match="CRC mismatch"):
        blob.read(p)
    c = blob.ctable(b, "fd_machine_map", "m.fdmap")
    assert f"fd_machine_map_size = {len(b)}u" in c and c.count("u,") == len(b) // 4


def test_generate_check_passes_on_committed_files():
    r = subprocess.run([sys.executable, "-m", "fluxdrive", "map", "generate", "--check"],
                       cwd=REPO, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr


def test_convert_cli_error_format(tmp_path):
    p = csv(tmp_path, "head.csv", "id,iq\n")
    r = subprocess.run([sys.executable, "-m", "fluxdrive", "map", "convert", str(p), "-o",
                        str(tmp_path / "x.fdmap")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert r.stderr.startswith(f"fluxdrive map: {p}: bad header: line 1: "), r.stderr
    ok = subprocess.run([sys.executable, "-m", "fluxdrive", "map", "convert",
                         str(REPO / "maps" / "pmasyr_file.npz"), "-o", str(tmp_path / "y.fdmap")],
                        capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0 and ok.stdout == "" and (tmp_path / "y.fdmap").is_file()


def test_doc_page_is_what_the_command_writes():
    """docs/flux-maps.md's generated part (numbers of every preset) equals
    what `fluxdrive map doc --write` would write."""
    r = subprocess.run([sys.executable, "-m", "fluxdrive", "map", "doc", "--check"], cwd=REPO,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr


def test_board_table_is_the_sil_blob(tmp_path):
    """The board's C table (map ctable) holds the very bytes the SIL loads
    (map convert) for the same map file: one generator path."""
    src = str(REPO / "maps" / "pmasyr_file.npz")
    run = [sys.executable, "-m", "fluxdrive", "map"]
    subprocess.run(run + ["convert", src, "-o", str(tmp_path / "m.fdmap")], check=True,
                   timeout=120)
    subprocess.run(run + ["ctable", src, "-o", str(tmp_path / "m.c")], check=True, timeout=120)
    words = [int(w[2:-2], 16) for w in (tmp_path / "m.c").read_text().split()
             if w.startswith("0x") and w.endswith("u,")]
    blob_bytes = (tmp_path / "m.fdmap").read_bytes()
    assert b"".join(w.to_bytes(4, "little") for w in words) == blob_bytes


def _sil_parse(tmp_path, machine, controller=None):
    """The real runner's verdict on a scenario (--print-config): (rc, text)."""
    from conftest import REAL_SIL

    if not REAL_SIL.is_file():
        pytest.skip(f"real runner not built ({REAL_SIL} missing)")
    sc = {"duration": 0.01, "machine": machine, "controller": controller or {}}
    p = tmp_path / "sc.json"
    p.write_text(json.dumps(sc))
    env = {**os.environ, "FLUXDRIVE_PYTHON": sys.executable,
           "PYTHONPATH": str(REPO / "tools" / "src")}
    r = subprocess.run([str(REAL_SIL), str(p), "--print-config"], capture_output=True, text=True,
                       timeout=120, env=env)
    return r.returncode, r.stdout + r.stderr


@pytest.mark.real_sil
def test_scenario_gives_the_pole_pairs(tmp_path):
    """Issue 23, point 13: a map file without pole_pairs takes the
    scenario's machine.pole_pairs; a file with others is refused naming
    both; without either the scenario key is named."""
    i_d, i_q, pd, pq = small()
    nopp = npz(tmp_path, "nopp.npz", i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq)
    rc, out = _sil_parse(tmp_path, {"map": str(nopp), "pole_pairs": 4}, {"i_max": 3})
    assert rc == 0, out
    assert '"pole_pairs":\t4' in out, out
    rc, out = _sil_parse(tmp_path, {"map": str(nopp)}, {"i_max": 3})
    assert rc != 0 and "machine.pole_pairs: required" in out and "nopp.npz" in out, out
    pp2 = npz(tmp_path, "pp2.npz", i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq, pole_pairs=2)
    rc, out = _sil_parse(tmp_path, {"map": str(pp2), "pole_pairs": 3}, {"i_max": 3})
    assert rc != 0 and "machine.pole_pairs: 3" in out and "the file has 2, 3 given" in out, out
    rc, out = _sil_parse(tmp_path, {"map": str(pp2), "pole_pairs": 2}, {"i_max": 3})
    assert rc == 0, out
    # the map tool itself: --pole-pairs fills a gap, never overrides
    assert io.load(nopp, pole_pairs=4).pole_pairs == 4
    refused(pp2, "pole pairs", "the file has 2, 3 given", pole_pairs=3)


@pytest.mark.real_sil
def test_i_max_within_the_map(tmp_path):
    """Issue 23, point 14: the drive's current limit beyond the map's grid
    (small(): +-4 A) is refused naming i_max and the grid; within, accepted."""
    i_d, i_q, pd, pq = small()
    p = npz(tmp_path, "m.npz", i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq, pole_pairs=2)
    rc, out = _sil_parse(tmp_path, {"map": str(p)}, {"i_max": 4.0, "i_trip": 6})
    assert rc == 0, out
    rc, out = _sil_parse(tmp_path, {"map": str(p)}, {"i_max": 4.5, "i_trip": 6})
    assert rc != 0, out
    assert "controller.i_max: 4.5 A reaches beyond the flux map" in out, out
    assert "(i_d -4 .. 4 A, i_q -4 .. 4 A)" in out and "at most 4 A" in out, out
    # a half-range map (i_d <= 0) holds all the drive needs
    h = npz(tmp_path, "h.npz", i_d=i_d[:5], i_q=i_q, psi_d=pd[:, :5], psi_q=pq[:, :5],
            pole_pairs=2)
    rc, out = _sil_parse(tmp_path, {"map": str(h)}, {"i_max": 4.0, "i_trip": 6})
    assert "controller.i_max" not in out, out
