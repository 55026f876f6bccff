"""`fluxdrive run` and `fluxdrive bench` against a fake runner (CLI contract)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import SIGNALS, assert_png, calls
from fluxdrive import sil
from fluxdrive.bench import parse_bench_output
from fluxdrive.cli import main
from fluxdrive.errors import FluxdriveError


def test_run_writes_log_summary_plot(fake_sil, scenario, tmp_path, capsys):
    sc = scenario("step")
    out = tmp_path / "out"
    rc = main(["run", str(sc), "--sil", str(fake_sil), "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    log = np.load(out / "log.npy")
    assert set(SIGNALS) <= set(log.dtype.names)
    assert json.loads((out / "summary.json").read_text())["passed"] is True
    assert_png(out / "plot.png")
    assert "scenario: speed step" in captured.out  # title from the scenario's name
    assert "speed.final" in captured.out
    assert f"plot:    {out / 'plot.png'}" in captured.out
    argv = calls(fake_sil)[-1]
    assert argv[0] == str(sc)
    assert argv[argv.index("--log") + 1] == str(out / "log.npy")
    assert argv[argv.index("--summary") + 1] == str(out / "summary.json")
    assert "--decimate" not in argv and "--bench" not in argv


def test_run_default_out_dir_decimate_and_plot_path(fake_sil, scenario, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sc = scenario("ramp")
    png = tmp_path / "pics" / "ramp.png"
    rc = main(["run", str(sc), "--sil", str(fake_sil), "--decimate", "4", "--plot", str(png),
               "--signals", "speed,speed_ref;i_a"])
    assert rc == 0
    assert (tmp_path / "out" / "ramp" / "log.npy").is_file()
    assert len(np.load(tmp_path / "out" / "ramp" / "log.npy")) == 0.05 * 16000 / 4
    assert_png(png)
    argv = calls(fake_sil)[-1]
    assert argv[argv.index("--decimate") + 1] == "4"


def test_run_sil_from_env(fake_sil, scenario, tmp_path, monkeypatch):
    monkeypatch.setenv("FLUXDRIVE_SIL", str(fake_sil))
    assert main(["run", str(scenario()), "--out", str(tmp_path / "o"), "--no-plot"]) == 0
    assert len(calls(fake_sil)) == 1
    assert not (tmp_path / "o" / "plot.png").exists()


def test_run_summary_from_stdout_when_no_file(fake_sil, scenario, tmp_path):
    out = tmp_path / "o"
    assert main(["run", str(scenario(no_summary_file=True)), "--sil", str(fake_sil),
                 "--out", str(out), "--no-plot"]) == 0
    assert json.loads((out / "summary.json").read_text())["scenario"] == "speed step"


def test_run_bad_scenario_propagates_exit_2(fake_sil, scenario, tmp_path, capsys):
    out = tmp_path / "o"
    rc = main(["run", str(scenario(duration=-1)), "--sil", str(fake_sil), "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2
    assert "field 'duration'" in err  # the runner's message is passed through
    assert "exit code 2" in err
    assert not (out / "plot.png").exists()


def test_run_other_exit_code_propagates(fake_sil, scenario, tmp_path, capsys):
    rc = main(["run", str(scenario(crash=True)), "--sil", str(fake_sil), "--out", str(tmp_path / "o")])
    assert rc == 3
    assert "internal error" in capsys.readouterr().err


def test_run_stale_outputs_removed(fake_sil, scenario, tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / "log.npy").write_bytes(b"stale")
    assert main(["run", str(scenario(crash=True)), "--sil", str(fake_sil), "--out", str(out)]) == 3
    assert not (out / "log.npy").exists()


def test_run_unknown_signal_exit_2(fake_sil, scenario, tmp_path, capsys):
    rc = main(["run", str(scenario()), "--sil", str(fake_sil), "--out", str(tmp_path / "o"),
               "--signals", "speed;nonsense"])
    assert rc == 2
    assert "unknown signal: nonsense" in capsys.readouterr().err


def test_run_missing_binary_gives_build_hint(scenario, tmp_path, capsys):
    rc = main(["run", str(scenario()), "--sil", str(tmp_path / "no-such-sil")])
    err = capsys.readouterr().err
    assert rc == 2
    assert "SIL runner not found" in err
    assert "cmake --preset host-release && cmake --build build/host-release" in err
    assert "Traceback" not in err


def test_run_non_executable_binary(scenario, tmp_path, capsys):
    f = tmp_path / "sil"
    f.write_text("#!/bin/sh\n")
    f.chmod(0o644)
    assert main(["run", str(scenario()), "--sil", str(f)]) == 2
    assert "not executable" in capsys.readouterr().err


def test_run_missing_scenario(fake_sil, tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.json"), "--sil", str(fake_sil)]) == 2
    assert "scenario not found" in capsys.readouterr().err
    assert calls(fake_sil) == []


def test_run_bad_decimate_is_usage_error(fake_sil, scenario, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["run", str(scenario()), "--sil", str(fake_sil), "--decimate", "0"])
    assert exc.value.code == 2


def test_bench_best_and_median(fake_sil, scenario, capsys):
    sc = scenario(rtf=[40.0, 80.0, 60.0])
    assert main(["bench", str(sc), "--sil", str(fake_sil)]) == 0
    out = capsys.readouterr().out
    assert out.count("run ") == 3
    assert "best real-time factor:   80.0" in out
    assert "median real-time factor: 60.0" in out
    assert all(c[-1] == "--bench" for c in calls(fake_sil))


def test_bench_repeat(fake_sil, scenario, capsys):
    assert main(["bench", str(scenario()), "--sil", str(fake_sil), "--repeat", "2"]) == 0
    assert len(calls(fake_sil)) == 2
    assert "steps 800" in capsys.readouterr().out


def test_bench_failure_propagates(fake_sil, scenario, capsys):
    assert main(["bench", str(scenario(duration=0)), "--sil", str(fake_sil)]) == 2
    assert "field 'duration'" in capsys.readouterr().err
    assert len(calls(fake_sil)) == 1


def test_parse_bench_output():
    run = parse_bench_output("steps: 16000\nwall: 0.125 s\nreal-time factor: 8.0\n")
    assert (run.rtf, run.steps, run.wall) == (8.0, 16000, 0.125)
    with pytest.raises(FluxdriveError, match="real-time factor"):
        parse_bench_output("nothing here")


def test_parse_summary_stdout():
    text = 'progress 10%\n{"x": 1}\nnoise\n{\n  "a": {"b": 2},\n  "c": [1, 2]\n}\n'
    assert sil.parse_summary_stdout(text) == {"a": {"b": 2}, "c": [1, 2]}
    assert sil.parse_summary_stdout("no json") is None


def test_locate_sil_default_is_repo_build_path(monkeypatch):
    root = sil.find_repo_root()
    assert root is not None and (root / "CMakePresets.json").is_file()
    expected = root / sil.SIL_RELPATH
    if expected.exists():
        assert sil.locate_sil() == expected.resolve()
    else:
        with pytest.raises(FluxdriveError) as exc:
            sil.locate_sil()
        assert str(expected) in exc.value.message
        assert "cmake --preset host-release" in exc.value.hint
