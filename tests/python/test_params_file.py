"""A parameter file over a scenario's drive (fluxdrive-sil --params,
sil/runner/scenario_params.h): the drive's set changes, the plant's machine
does not; every bad file is refused naming the file and the parameter."""

from __future__ import annotations

import json
import os
import subprocess

import pytest

from conftest import DEFAULT_SCENARIO, REAL_SIL

pytestmark = pytest.mark.skipif(not REAL_SIL.exists(), reason="fluxdrive-sil not built")


def _config(tmp_path, params: dict | str, env: bool = False) -> subprocess.CompletedProcess:
    p = tmp_path / "params.json"
    p.write_text(params if isinstance(params, str) else json.dumps(params))
    args = [str(REAL_SIL), str(DEFAULT_SCENARIO), "--print-config"]
    e = dict(os.environ)
    e.pop("FLUXDRIVE_PARAMS", None)
    if env:
        e["FLUXDRIVE_PARAMS"] = str(p)
    else:
        args += ["--params", str(p)]
    return subprocess.run(args, capture_output=True, text=True, timeout=60, env=e)


def test_drive_takes_the_file_plant_keeps_its_machine(tmp_path):
    base = json.loads(_config(tmp_path, {}).stdout)
    for env in (False, True):
        r = _config(tmp_path, {"rs": 0.5, "ld": 1e-3, "inertia": 0.03, "pos_source": "encoder",
                               "identified": {"rs": {"status": "done"}}}, env)
        assert r.returncode == 0, r.stderr
        cfg = json.loads(r.stdout)
        assert cfg["controller"]["rs"] == pytest.approx(0.5)
        assert cfg["controller"]["ld"] == pytest.approx(1e-3)
        assert cfg["controller"]["inertia"] == pytest.approx(0.03)
        assert cfg["machine"] == base["machine"]  # the plant's truth untouched
        assert "parameters from" in r.stderr


@pytest.mark.parametrize("params, want", [
    ({"rs": -1}, "rs: -1 outside"),
    ({"rsx": 1}, "rsx: not a drive parameter"),
    ({"rs": "a"}, "rs: must be a number"),
    ({"pos_source": "gps"}, "pos_source: must be one of the names"),
    ({"slow_div": 2.5}, "slow_div: 2.5 outside"),
    ({"map": "maps/syr_1k1.fdmap"}, "map: needs a flux-map machine"),
    ("[1, 2]", "not a JSON object of parameters"),
    ("{", "not a JSON object of parameters"),
])
def test_bad_files_are_refused_by_name(tmp_path, params, want):
    r = _config(tmp_path, params)
    assert r.returncode == 2
    assert want in r.stderr, r.stderr
    assert "params.json" in r.stderr
