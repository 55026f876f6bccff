"""Measured-map files as a new user brings them (issue 23, points 9-12):
motulator's published layout (complex i_s_dq, psi_s_dq, rows holding one
i_d, PM on +d, peak amperes), the convention and the units checked against
the data, half-range maps (i_d <= 0).

The files are made here from the analytic model (a PM-assisted SyR machine,
Hinkkanen 2017 with a PM term, tools/src/fluxdrive/fluxmap/presets.py) on a
21 x 27 grid like the published one; the reference torque comes from the
model itself (a dense angle sweep), never from the tools.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import REAL_SIL
from fluxdrive.fluxmap import FluxMapError, blob, io
from fluxdrive.fluxmap.luts import tables
from fluxdrive.fluxmap.model import fluxdrive_to_syr
from fluxdrive.fluxmap.presets import _scaled, grid_syr

REPO = Path(__file__).resolve().parents[2]
MODEL = _scaled(0.6, 1.5, 3.0, psi_pm=0.12)  # PM-SyR, 0.12 Vs, MTPA about 40 N m at 20 A
P = 2
ID = np.linspace(-20.0, 20.0, 21)
IQ = np.linspace(-26.0, 26.0, 27)


def fd_flux(i_d, i_q):
    """The model's flux in fluxdrive's frame (the model is in SyR's)."""
    pd, pq = MODEL.flux(np.asarray(i_q, float), -np.asarray(i_d, float))
    return -pq, pd


def mtpa_reference(amp: float) -> float:
    """The model's largest torque at current amplitude amp (dense sweep)."""
    th = np.linspace(0.0, np.pi, 20001)
    i_d, i_q = amp * np.cos(th), amp * np.sin(th)
    pd, pq = fd_flux(i_d, i_q)
    return float(np.max(1.5 * P * (pd * i_q - pq * i_d)))


def published(tmp: Path, name: str, i_d=ID, i_q=IQ, flux=1.0, cur=1.0, swap=False, **extra):
    """The published layout: complex arrays whose rows hold one i_d."""
    D, Q = np.meshgrid(i_d, i_q, indexing="ij")
    pd, pq = fd_flux(D, Q)
    i_s, psi_s = cur * (D + 1j * Q), flux * (pd + 1j * pq)
    if swap:  # d and q exchanged
        i_s, psi_s = cur * (Q + 1j * D), flux * (pq + 1j * pd)
    p = tmp / name
    np.savez(p, i_s_dq=i_s, psi_s_dq=psi_s, pole_pairs=np.array(P), **extra)
    return p


def refused(path, *parts, **kw):
    with pytest.raises(FluxMapError) as e:
        io.load(path, **kw)
    msg = str(e.value)
    print(msg)
    for s in (str(path), *parts):
        assert s in msg, msg
    return msg


def cli(*args):
    return subprocess.run([sys.executable, "-m", "fluxdrive", "map", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def mtpa_at(m, amp):
    t = tables(m)
    return float(np.interp(amp, t.amp, t.amp_t))


# --- point 9: both orientations -------------------------------------------------------------


def test_published_layout_is_read_transposed(tmp_path):
    m = io.load(published(tmp_path, "pub.npz"))
    assert (m.nd, m.nq) == (21, 27)
    assert np.array_equal(m.i_d, ID) and np.array_equal(m.i_q, IQ)
    assert any("rows hold one i_d, columns one i_q (read transposed)" in n for n in m.notes)
    # the same points in fluxdrive's own layout (rows holding one i_q): the same blob
    D, Q = np.meshgrid(ID, IQ)
    pd, pq = fd_flux(D, Q)
    np.savez(tmp_path / "rows_iq.npz", i_s_dq=D + 1j * Q, psi_s_dq=pd + 1j * pq, pole_pairs=P)
    other = io.load(tmp_path / "rows_iq.npz")
    assert any("rows hold one i_q, columns one i_d" in n for n in other.notes)
    assert blob.to_bytes(m) == blob.to_bytes(other)
    # and the machine it describes is the model's: MTPA torque at 20 A
    t, ref = mtpa_at(m, 20.0), mtpa_reference(20.0)
    print(f"MTPA at 20 A: {t:.3f} N m from the file, {ref:.3f} N m from the model")
    assert abs(t / ref - 1) < 0.005
    r = cli("check", tmp_path / "pub.npz")
    assert r.returncode == 0, r.stderr
    assert "layout: complex arrays 21 x 27, rows hold one i_d, columns one i_q" in r.stdout


def test_irregular_grid_keeps_its_message(tmp_path):
    D, Q = np.meshgrid(ID, IQ, indexing="ij")
    i_s = D + 1j * Q
    i_s[4, 7] += 0.3  # one point off the grid: neither orientation
    pd, pq = fd_flux(D, Q)
    np.savez(tmp_path / "skew.npz", i_s_dq=i_s, psi_s_dq=pd + 1j * pq, pole_pairs=P)
    refused(tmp_path / "skew.npz", "irregular grid", "not a grid in either orientation")


# --- point 10: the convention the data show ------------------------------------------------


def test_convention_contradicting_the_data_is_refused(tmp_path):
    pub = published(tmp_path, "pub.npz")
    ref = blob.to_bytes(io.load(pub))
    # stated syr on a PM-on-+d map (would simulate another machine)
    refused(pub, "convention syr contradicts the data", "PM flux at zero current on +d",
            "larger incremental inductance at zero current on q", "--convention fluxdrive",
            convention="syr")
    refused(published(tmp_path, "pubsyr.npz", convention=np.array("syr")),
            "convention syr contradicts the data")
    # d and q exchanged: neither convention
    refused(published(tmp_path, "swap.npz", swap=True), "the data fit neither",
            "PM flux at zero current on +q", "d and q exchanged")
    refused(published(tmp_path, "swap2.npz", swap=True), "the data fit neither",
            convention="fluxdrive")
    # the same map in the SyR convention: stated fluxdrive refused, unstated detected
    D, Q = np.meshgrid(ID, IQ)
    sd, sq, spd, spq = fluxdrive_to_syr(ID, IQ, *fd_flux(D, Q))
    np.savez(tmp_path / "syr.npz", i_d=sd, i_q=sq, psi_d=spd, psi_q=spq, pole_pairs=P)
    refused(tmp_path / "syr.npz", "convention fluxdrive contradicts the data",
            "PM flux at zero current on -q", "--convention syr", convention="fluxdrive")
    m = io.load(tmp_path / "syr.npz")
    assert any(n.startswith("convention: syr (not stated: detected") for n in m.notes)
    assert blob.to_bytes(m) == ref
    # no PM (syr_1k1): the saliency decides
    i_d, i_q, pd, pq = grid_syr("syr_1k1")
    np.savez(tmp_path / "syr1k1.npz", i_d=i_d, i_q=i_q, psi_d=pd, psi_q=pq, pole_pairs=P)
    refused(tmp_path / "syr1k1.npz", "convention fluxdrive contradicts the data",
            "no PM flux at zero current", "larger incremental inductance at zero current on d",
            convention="fluxdrive")
    m = io.load(tmp_path / "syr1k1.npz", convention="syr")
    assert abs(m.pm_flux()) < 1e-9
    r = cli("convert", pub, "-o", tmp_path / "x.fdmap", "--convention", "syr")
    assert r.returncode == 2 and "contradicts the data" in r.stderr, r.stderr
    assert not (tmp_path / "x.fdmap").exists()


# --- point 11: units --------------------------------------------------------------------------


def test_flux_units_checked(tmp_path):
    ref = io.load(published(tmp_path, "pub.npz"))
    for k in (1000.0, 500.0):
        refused(published(tmp_path, f"x{k:g}.npz", flux=k), "flux linkages implausible (unit?)",
                "beyond any machine", "divide by 1000 or pass --flux-unit mVs")
    m = io.load(tmp_path / "x1000.npz", flux_unit="mVs")
    assert np.allclose(m.psi_d, ref.psi_d, rtol=1e-12) and np.allclose(m.psi_q, ref.psi_q)
    np.savez(tmp_path / "unit.npz", **dict(np.load(tmp_path / "x1000.npz")),
             flux_unit=np.array("mVs"))
    assert np.allclose(io.load(tmp_path / "unit.npz").psi_d, ref.psi_d)
    r = cli("check", tmp_path / "x1000.npz")
    assert r.returncode == 2 and "--flux-unit mVs" in r.stderr, r.stderr
    r = cli("convert", tmp_path / "x500.npz", "-o", tmp_path / "x.fdmap")
    assert r.returncode == 2 and "flux linkages implausible" in r.stderr, r.stderr


def small_pm(tmp, name, flux=1.0, cur=1.0):
    """A small PM motor (5 mVs, 40 / 60 uH, 4 pole pairs, 20 A grid)."""
    a = np.linspace(-20.0, 20.0, 11)
    D, Q = np.meshgrid(a, a)
    pd, pq = 0.005 + 40e-6 * D, 60e-6 * Q
    np.savez(tmp / name, i_d=cur * a, i_q=cur * a, psi_d=flux * pd, psi_q=flux * pq,
             pole_pairs=np.array(4))
    return tmp / name


def test_flux_unit_against_voltage_and_speed(tmp_path):
    """5 mVs in mVs reads as 5 Vs, a plausible flux for some machine: only
    the voltage at the stated speed shows it (48 V link, 6000 rpm)."""
    p = small_pm(tmp_path, "mvs.npz", flux=1000.0)
    io.load(p)  # alone: a plausible (larger) machine
    refused(p, "flux linkages implausible (unit?)", "phase peak at 6000 rpm",
            "--flux-unit mVs", v_dc=48.0, speed_rpm=6000.0)
    m = io.load(p, flux_unit="mVs", v_dc=48.0, speed_rpm=6000.0)
    assert m.pm_flux() == pytest.approx(0.005)
    assert not any(n.startswith("warning") for n in m.notes)  # 12.6 V at 6000 rpm < 27.7 V


def test_current_units_checked(tmp_path):
    ref = io.load(published(tmp_path, "pub.npz"))
    ma = published(tmp_path, "ma.npz", cur=1000.0)
    refused(ma, "currents implausible (unit?)", "currents in mA", "--current-unit mA", i_max=20.0)
    m = io.load(ma, current_unit="mA", i_max=20.0)
    assert np.allclose(m.i_d, ref.i_d) and np.allclose(m.psi_d, ref.psi_d)
    # a small motor in mA: 40 nH is below any machine, with no i_max known
    refused(small_pm(tmp_path, "small_ma.npz", cur=1000.0), "inductance implausible (unit?)",
            "currents in mA")
    r = cli("check", ma, "--i-max", "20")
    assert r.returncode == 2 and "--current-unit mA" in r.stderr, r.stderr


# --- point 12: half-range maps --------------------------------------------------------------


def test_half_range_map_gives_the_full_tables(tmp_path):
    full = io.load(published(tmp_path, "full.npz"))
    half = io.load(published(tmp_path, "half.npz", i_d=ID[ID <= 0]))
    assert (half.nd, half.i_d[-1]) == (11, 0.0)
    tf, th = tables(full), tables(half)
    ref = mtpa_reference(20.0)
    print(f"MTPA table range: full {tf.mtpa_t_max:.3f}, half {th.mtpa_t_max:.3f} N m; model at "
          f"20 A {ref:.3f} N m")
    assert abs(th.mtpa_t_max / ref - 1) < 0.005
    assert abs(th.mtpa_t_max / tf.mtpa_t_max - 1) < 1e-6
    assert np.max(np.abs(th.mtpa_id - tf.mtpa_id)) < 1e-3 * 20
    assert np.max(np.abs(th.mtpa_iq - tf.mtpa_iq)) < 1e-3 * 20
    assert np.all(th.mtpa_id <= 0)
    r = cli("check", tmp_path / "half.npz")
    assert r.returncode == 0, r.stderr
    assert f"MTPA table: 0 .. {th.mtpa_t_max:.3f} N m (current amplitude up to 20.00 A)" in r.stdout


def test_maps_that_cannot_hold_the_mtpa_are_refused(tmp_path):
    refused(published(tmp_path, "pos.npz", i_d=ID[ID >= 0]), "i_d range cannot hold the MTPA",
            "give the map for i_d <= 0")
    # reverse saliency (L_d 20 mH > L_q 5 mH, PM on +d): its MTPA is at i_d > 0
    a = np.linspace(-20.0, 0.0, 11)
    b = np.linspace(-20.0, 20.0, 21)
    D, Q = np.meshgrid(a, b)
    np.savez(tmp_path / "rev.npz", i_d=a, i_q=b, psi_d=0.1 + 0.02 * D, psi_q=0.005 * Q,
             pole_pairs=np.array(2))
    refused(tmp_path / "rev.npz", "MTPA beyond the map's i_d range", "i_d > 0 A")
    r = cli("convert", tmp_path / "rev.npz", "-o", tmp_path / "rev.fdmap")
    assert r.returncode == 2 and not (tmp_path / "rev.fdmap").exists()


@pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")
def test_half_range_map_runs_in_the_sil(tmp_path):
    """FOC torque mode at 30 N m, 500 rpm, on the half map and the full one."""
    published(tmp_path, "full.npz")
    published(tmp_path, "half.npz", i_d=ID[ID <= 0])
    out = {}
    for name in ("full", "half"):
        sc = {"name": name, "duration": 0.25, "machine": {"map": f"{name}.npz", "rs": 0.5},
              "sensors": {"i_full_scale": 40, "v_full_scale": 1000}, "dc_link": {"voltage": 540},
              "mechanics": {"mode": "imposed",
                            "speed": {"unit": "rpm", "terms": [{"type": "const", "value": 500}]}},
              "controller": {"law": "foc", "mode": "torque", "i_max": 20, "i_trip": 30,
                             "torque_max": 40, "v_dc_max": 700, "v_dc_min": 300},
              "references": {"torque": [{"type": "step", "t": 0.05, "value": 30}]}}
        (tmp_path / f"{name}.json").write_text(json.dumps(sc))
        r = subprocess.run([str(REAL_SIL), str(tmp_path / f"{name}.json"), "--summary",
                            str(tmp_path / f"{name}.sum.json")], capture_output=True, text=True,
                           timeout=300, env={**os.environ, "FLUXDRIVE_PYTHON": sys.executable})
        assert r.returncode == 0, r.stdout + r.stderr
        out[name] = json.loads((tmp_path / f"{name}.sum.json").read_text())
    for name, s in out.items():
        print(f"{name}: {s['final_torque']:.3f} N m, {s['max_phase_current']:.2f} A")
        assert s["faults"] == [] and s["final_state"] == "run"
        assert abs(s["final_torque"] / 30.0 - 1) < 0.01
    assert abs(out["half"]["final_torque"] - out["full"]["final_torque"]) < 0.003 * 30


@pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")
def test_map_in_ma_is_refused_by_the_sil(tmp_path):
    """The published map with its currents in mA, run by a scenario with
    i_max 20 A: refused at set-up naming the unit (the SIL checks the grid
    against controller.i_max like `map check --i-max`); the same map with
    current_unit "mA" stated in the file runs."""
    published(tmp_path, "ma.npz", cur=1000.0)
    published(tmp_path, "ma_stated.npz", cur=1000.0, current_unit=np.array("mA"))
    for name, ok in (("ma", False), ("ma_stated", True)):
        sc = {"name": name, "duration": 0.05, "machine": {"map": f"{name}.npz", "rs": 0.5},
              "sensors": {"i_full_scale": 40, "v_full_scale": 1000}, "dc_link": {"voltage": 540},
              "controller": {"law": "foc", "mode": "torque", "i_max": 20, "i_trip": 30,
                             "torque_max": 40, "v_dc_max": 700, "v_dc_min": 300}}
        (tmp_path / f"{name}.json").write_text(json.dumps(sc))
        r = subprocess.run([str(REAL_SIL), str(tmp_path / f"{name}.json")], capture_output=True,
                           text=True, timeout=300,
                           env={**os.environ, "FLUXDRIVE_PYTHON": sys.executable})
        print(name, r.returncode, r.stderr.strip()[:300])
        if ok:
            assert r.returncode == 0, r.stderr
        else:
            assert r.returncode == 2, r.stderr
            assert "currents implausible (unit?)" in r.stderr and "mA" in r.stderr
