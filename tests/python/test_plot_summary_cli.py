"""`fluxdrive plot` and `fluxdrive summary` on synthetic data."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from conftest import assert_png, make_log
from fluxdrive.cli import main
from fluxdrive.plotting import plot_log
from fluxdrive.summary import flatten, format_summary


def test_plot_default_groups(log_file, capsys):
    out = log_file.parent / "p.png"
    assert main(["plot", str(log_file), "--out", str(out)]) == 0
    assert_png(out)
    assert str(out) in capsys.readouterr().out


def test_plot_default_output_path(log_file):
    assert main(["plot", str(log_file)]) == 0
    assert_png(log_file.with_suffix(".png"))


def test_plot_custom_groups_and_window(log_file):
    out = log_file.parent / "w.png"
    rc = main(["plot", str(log_file), "--signals", "i_d,i_q;flux,flux_ref;state,faults",
               "--t0", "0.01", "--t1", "0.1", "--out", str(out)])
    assert rc == 0
    assert_png(out)


def test_plot_unknown_signal_exit_2(log_file, capsys):
    out = log_file.parent / "x.png"
    rc = main(["plot", str(log_file), "--signals", "speed,sped;torque", "--out", str(out)])
    assert rc == 2
    err = capsys.readouterr().err
    assert "unknown signal: sped" in err
    assert "available signals: t, speed," in err
    assert "Traceback" not in err
    assert not out.exists()


def test_plot_missing_log_exit_2(tmp_path, capsys):
    assert main(["plot", str(tmp_path / "none.npy")]) == 2
    assert "log file not found" in capsys.readouterr().err


def test_plot_empty_window_exit_2(log_file, capsys):
    assert main(["plot", str(log_file), "--t0", "100"]) == 2
    assert "no samples" in capsys.readouterr().err


def test_plot_log_large_log_is_strided(tmp_path):
    log = make_log(n=450_000, names=["t", "speed", "speed_ref"])
    out = plot_log(log, [["speed", "speed_ref"]], tmp_path / "big.png", title="big")
    assert_png(out)


def test_summary_pretty_print(tmp_path, capsys):
    path = tmp_path / "summary.json"
    path.write_text(json.dumps({"scenario": "speed step", "steps": 16000,
                                "speed": {"rise_time": 0.0123456789, "overshoot": 0.02},
                                "passed": True, "faults": []}))
    assert main(["summary", str(path)]) == 0
    out = capsys.readouterr().out
    assert "speed.rise_time  0.0123457" in out
    assert "passed" in out and "true" in out
    assert "scenario" in out and "speed step" in out


def test_summary_json_flag(tmp_path, capsys):
    path = tmp_path / "s.json"
    path.write_text('{"a": 1}')
    assert main(["summary", "--json", str(path)]) == 0
    assert json.loads(capsys.readouterr().out) == {"a": 1}


def test_summary_bad_input_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["summary", str(bad)]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    arr = tmp_path / "arr.json"
    arr.write_text("[1, 2]")
    assert main(["summary", str(arr)]) == 2
    assert main(["summary", str(tmp_path / "missing.json")]) == 2


def test_format_summary_helpers():
    assert flatten({"a": {"b": 1, "c": {"d": 2}}, "e": {}}) == [("a.b", 1), ("a.c.d", 2), ("e", {})]
    text = format_summary({"x": 1.5e-6, "long_name": 3}, title="T")
    assert text.splitlines()[:2] == ["T", "="]
    assert "1.5000e-06" in text


def test_entry_point_no_traceback_for_user_errors(tmp_path):
    """The installed module, as a user runs it: a bad path gives one line, exit 2."""
    proc = subprocess.run([sys.executable, "-m", "fluxdrive", "plot", str(tmp_path / "x.npy")],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith("fluxdrive: error: log file not found")


def test_synthetic_log_is_little_endian_float64(log_file):
    log = np.load(log_file)
    assert all(log.dtype[n] == np.dtype("<f8") for n in log.dtype.names)
