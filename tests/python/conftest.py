"""Shared fixtures for the fluxdrive tools tests.

The real SIL runner may not be built, so most tests use synthetic logs and a
small fake runner script that honours the runner's CLI contract.
"""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
# CTest sets FLUXDRIVE_SIL to the runner of the build under test.
REAL_SIL = Path(os.environ.get("FLUXDRIVE_SIL") or REPO_ROOT / "build" / "host-release" / "sil" / "fluxdrive-sil")
DEFAULT_SCENARIO = REPO_ROOT / "sil" / "scenarios" / "default.json"

#: Signals the runner's log must contain (runner contract).
SIGNALS = [
    "t", "speed", "speed_est", "speed_ref", "torque", "torque_ref", "torque_est",
    "i_a", "i_b", "i_c", "i_d", "i_q", "v_dc", "duty_a", "duty_b", "duty_c",
    "flux", "flux_ref", "delta", "i_qs", "i_qs_ref", "state", "faults", "theta_e",
]


def run_sil(sc: dict, timeout: float = 300.0) -> np.ndarray | str:
    """Runs the real fluxdrive-sil on the scenario `sc` (a dict, written to a
    temporary file) with its log: the log as a structured array, or the
    runner's stderr (stripped) when it refused or failed. Shared by the
    start tests (test_held_start.py, test_start_polarity.py)."""
    with tempfile.TemporaryDirectory() as d:
        p = os.path.join(d, "sc.json")
        with open(p, "w") as f:
            json.dump(sc, f)
        r = subprocess.run([str(REAL_SIL), p, "--log", p + ".npy"], capture_output=True,
                           text=True, timeout=timeout)
        if r.returncode != 0:
            return r.stderr.strip()
        return np.load(p + ".npy")


def make_log(n: int = 2000, dt: float = 1.0 / 16000.0, names: list[str] | None = None) -> np.ndarray:
    """A synthetic log: 1-D structured array of little-endian float64 signals."""
    names = names or SIGNALS
    log = np.zeros(n, dtype=[(s, "<f8") for s in names])
    t = np.arange(n) * dt
    log["t"] = t
    w = 2 * np.pi * 50.0
    for i, s in enumerate(names):
        if s == "t":
            continue
        if s.startswith("i_") and s[-1] in "abc":
            phase = "abc".index(s[-1]) * 2 * np.pi / 3
            log[s] = 10.0 * np.sin(w * t - phase)
        elif s in ("state", "faults"):
            log[s] = (t > t[-1] / 2).astype(float)
        else:
            log[s] = np.tanh(t * 20.0) * (i + 1)
    return log


def pytest_addoption(parser: pytest.Parser) -> None:
    # test_random_machines.py: draw more machines (docs/machines.md)
    parser.addoption("--seed", action="append", type=int, default=[],
                     help="seed of a random machine (repeatable; test_random_machines.py)")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "real_sil: runs the real fluxdrive-sil binary (skipped when it is not built)"
    )
    # matplotlib 3.8 calls pyparsing APIs that pyparsing >= 3.3 marks deprecated.
    config.addinivalue_line("filterwarnings", r"ignore:.*deprecated:DeprecationWarning:matplotlib\..*")


@pytest.fixture
def log_file(tmp_path: Path) -> Path:
    path = tmp_path / "log.npy"
    np.save(path, make_log())
    return path


@pytest.fixture(autouse=True)
def _isolate_env(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """No test depends on the caller's $FLUXDRIVE_SIL; matplotlib stays headless."""
    monkeypatch.delenv("FLUXDRIVE_SIL", raising=False)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / ".mpl"))


FAKE_RUNNER = r'''
"""Fake fluxdrive-sil honouring the runner CLI contract (for tests)."""
import argparse, json, sys
from pathlib import Path
import numpy as np

SIGNALS = __SIGNALS__

p = argparse.ArgumentParser()
p.add_argument("scenario")
p.add_argument("--log")
p.add_argument("--summary")
p.add_argument("--decimate", type=int, default=1)
p.add_argument("--bench", action="store_true")
a = p.parse_args()

record = Path(__file__).with_suffix(".calls")
with open(record, "a") as fh:
    fh.write(json.dumps(sys.argv[1:]) + "\n")

try:
    sc = json.loads(Path(a.scenario).read_text())
except (OSError, ValueError) as e:
    print(f"fluxdrive-sil: cannot read scenario {a.scenario}: {e}", file=sys.stderr)
    sys.exit(2)
if not isinstance(sc.get("duration"), (int, float)) or sc["duration"] <= 0:
    print("fluxdrive-sil: scenario field 'duration' must be a positive number", file=sys.stderr)
    sys.exit(2)
if sc.get("crash"):
    print("fluxdrive-sil: internal error", file=sys.stderr)
    sys.exit(3)

n = int(sc["duration"] * 16000) // a.decimate
if a.bench:
    rtf = sc.get("rtf", [50.0])
    k = len(record.read_text().splitlines()) - 1
    print(f"steps: {n}")
    print(f"wall: {sc['duration'] / rtf[k % len(rtf)]:.6f} s")
    print(f"real-time factor: {rtf[k % len(rtf)]:.1f}")
    sys.exit(0)

log = np.zeros(n, dtype=[(s, "<f8") for s in SIGNALS])
log["t"] = np.arange(n) * a.decimate / 16000.0
log["speed"] = 100.0 * (1 - np.exp(-log["t"] / 0.01))
log["speed_ref"] = 100.0
log["torque"] = np.exp(-log["t"] / 0.01)
log["i_a"] = np.sin(2 * np.pi * 50 * log["t"])
summary = {"scenario": sc.get("name", "fake"), "steps": n,
           "speed": {"final": float(log["speed"][-1]), "overshoot": 0.0},
           "faults": 0, "passed": True}
if a.log:
    np.save(a.log, log)
if a.summary and not sc.get("no_summary_file"):
    Path(a.summary).write_text(json.dumps(summary))
print("fluxdrive-sil: simulating", sc.get("name", "?"))
print(json.dumps(summary, indent=2))
'''


@pytest.fixture
def fake_sil(tmp_path: Path) -> Path:
    """An executable fake runner; its calls are appended to fake-sil.calls."""
    path = tmp_path / "bin" / "fake-sil"
    path.parent.mkdir()
    body = FAKE_RUNNER.replace("__SIGNALS__", repr(SIGNALS))
    path.write_text(f"#!{sys.executable}\n" + textwrap.dedent(body))
    path.chmod(path.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    return path


@pytest.fixture
def scenario(tmp_path: Path):
    """Factory writing a scenario JSON file; returns its path."""

    def _make(stem: str = "step", **fields) -> Path:
        data = {"name": "speed step", "duration": 0.05}
        data.update(fields)
        path = tmp_path / "scenarios" / f"{stem}.json"
        path.parent.mkdir(exist_ok=True)
        path.write_text(json.dumps(data))
        return path

    return _make


def calls(fake: Path) -> list[list[str]]:
    rec = fake.with_suffix(".calls")
    if not rec.exists():
        return []
    return [json.loads(line) for line in rec.read_text().splitlines()]


PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def assert_png(path: Path, min_size: int = 5000) -> None:
    assert path.is_file(), f"no plot at {path}"
    data = path.read_bytes()
    assert data[:8] == PNG_MAGIC
    assert len(data) > min_size, f"plot suspiciously small ({len(data)} bytes)"

