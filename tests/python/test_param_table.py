"""The one parameter table (firmware/app/drive_param_table.h) walked field by
field through the scenario parser of the real runner: every parameter's
scenario key accepts its default, refuses a value just outside each end of
its range with an error that names that key (one range for parser and
drive), and lands in the drive's configuration (``--print-config``). The
DBC, the tools' table and docs/parameters.md are checked against the same
table by CTest ``params/agreement`` (``fluxdrive params --check``).
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from conftest import REAL_SIL
from fluxdrive import params

pytestmark = [
    pytest.mark.real_sil,
    pytest.mark.skipif(not REAL_SIL.is_file(), reason=f"fluxdrive-sil not built ({REAL_SIL})"),
]

ENUMS = {"law": "laws", "mode": "modes", "pos_source": "pos_sources"}


def table() -> dict:
    return params.from_sil(REAL_SIL)


def scenario(tmp: Path, key: str, value) -> Path:
    """A scenario setting one key ("section.name"); pwm_frequency from ts."""
    section, name = key.split(".")
    sc = {"name": "param walk", "duration": 0.01, section: {name: value}}
    if key == "controller.mode" and value == "current":
        sc["controller"]["law"] = "foc"
    if key == "controller.pos_source" and value != "encoder" and not str(value).startswith("no_such"):
        # a star-point source: the window's edges, a star point, the alignment
        sc["controller"]["align_time"] = 0.01
        sc["inverter"] = {"model": "switching"}
        sc["board"] = {"asym_edges": 1}
        sc["machine"] = {"preset": "fabbri2022_t51"}
    p = tmp / "walk.json"
    p.write_text(json.dumps(sc))
    return p


def run(path: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(REAL_SIL), str(path), "--print-config"], capture_output=True,
                          text=True, timeout=60)


def as_scenario_value(p: dict, v: float):
    if p["scenario"] == "inverter.pwm_frequency":
        return 1.0 / v  # the key sets ts = 1 / pwm_frequency
    if p["type"] in ("u16", "u32"):
        return int(round(v))
    return v


def test_tools_table_is_the_firmware_table():
    assert params.tables() == table(), "run: fluxdrive params --write"


def map_crc24(path: Path) -> int:
    blob = path.read_bytes()
    return int.from_bytes(blob[-4:], "little") & 0xFFFFFF


@pytest.mark.parametrize("p", table()["params"], ids=lambda p: p["name"])
def test_every_parameter_through_its_scenario_key(p, tmp_path):
    t = table()
    key = p["scenario"]
    if p["type"] == "map":  # a file, read as its blob's CRC (docs/flux-maps.md)
        repo = Path(__file__).resolve().parents[2]
        blob = repo / "maps" / "syr_1k1.fdmap"
        r = run(scenario(tmp_path, key, str(blob)))
        assert r.returncode == 0, (key, r.stderr)
        cfg = json.loads(r.stdout)
        assert cfg["controller"][p["name"]] == map_crc24(blob)
        assert cfg["machine"]["kind"] == "flux_map"
        for bad, why in ((1.0, "must be a file name"), ("no_such.fdmap", "cannot open")):
            r = run(scenario(tmp_path, key, bad))
            assert r.returncode == 2 and f"{key}: " in r.stderr and why in r.stderr, r.stderr
        return
    if p["type"] in ENUMS:
        names = t[ENUMS[p["type"]]]
        for name in names:
            r = run(scenario(tmp_path, key, name))
            assert r.returncode == 0, (key, name, r.stderr)
            assert json.loads(r.stdout)["controller"][p["name"]] == name
        r = run(scenario(tmp_path, key, "no_such_" + p["name"]))
        assert r.returncode == 2 and f"{key}: must be one of: {', '.join(names)}" in r.stderr
        return
    # the default lands in the drive's set
    r = run(scenario(tmp_path, key, as_scenario_value(p, p["default"])))
    assert r.returncode == 0, (key, r.stderr)
    got = json.loads(r.stdout)["controller"][p["name"]]
    assert got == pytest.approx(p["default"], rel=1e-6, abs=1e-12), key
    # just outside each end of the range: refused, the key named
    lo, hi = p["min"], p["max"]
    step = max(abs(hi) * 1e-3, 1.0 if p["type"] != "f32" else 1e-9)
    outside = [hi + step]
    if key != "inverter.pwm_frequency" or lo > 0:
        outside.append(lo - max(abs(lo) * 1e-3, step))
    for v in outside:
        if key == "inverter.pwm_frequency" and v <= 0:
            continue
        r = run(scenario(tmp_path, key, as_scenario_value(p, v)))
        assert r.returncode == 2, (key, v, r.stdout)
        assert f"{key}: " in r.stderr, (key, v, r.stderr)
