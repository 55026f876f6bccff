"""``fluxdrive pil`` without QEMU: defaults, builds of missing artefacts,
absolute paths, --isrs all, the checks."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from fluxdrive import cm4_cycles as cm
from fluxdrive import pil, sil
from fluxdrive.cli import _isrs, build_parser
from fluxdrive.errors import FluxdriveError


@pytest.fixture
def repo(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An empty repo root (cwd) with nothing built; builds are recorded."""
    root = tmp_path / "repo"
    (root / "sil").mkdir(parents=True)
    (root / "CMakePresets.json").write_text("{}")
    monkeypatch.chdir(root)
    monkeypatch.delenv(pil.ENV_ELF, raising=False)
    monkeypatch.delenv(sil.ENV_SIL, raising=False)
    monkeypatch.setattr(sil, "find_repo_root", lambda start=None: root)
    return root


def fake_build(monkeypatch: pytest.MonkeyPatch, produce: dict[str, Path]) -> list[list[str]]:
    """subprocess.run stand-in: records cmake calls; a build creates its artefact."""
    done: list[list[str]] = []

    class R:
        returncode = 0

    def run(argv, cwd=None, check=False):
        done.append(list(argv))
        for target, path in produce.items():
            if "--build" in argv and target in argv:
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text("")
                path.chmod(0o755)
        return R()

    monkeypatch.setattr(pil.subprocess, "run", run)
    return done


def test_default_elf_is_built_when_missing(repo, monkeypatch, capsys) -> None:
    elf = repo / pil.ELF_RELPATH
    done = fake_build(monkeypatch, {"fluxdrive-pil.elf": elf})
    monkeypatch.setattr(pil.shutil, "which", lambda name: f"/usr/bin/{name}")
    assert pil.locate_elf(None) == elf.resolve()
    assert done == [list(a) for a in pil.ELF_BUILD]
    assert "PIL image missing, building it: cmake --preset cortex-m4f" in capsys.readouterr().out
    done.clear()
    assert pil.locate_elf(None) == elf.resolve()  # present: not built again
    assert done == []


def test_default_elf_without_cross_compiler(repo, monkeypatch) -> None:
    done = fake_build(monkeypatch, {})
    monkeypatch.setattr(pil.shutil, "which", lambda name: None)
    with pytest.raises(FluxdriveError, match="needs arm-none-eabi-gcc, not found") as e:
        pil.locate_elf(None)
    assert "gcc-arm-none-eabi" in (e.value.hint or "")
    assert done == []


def test_explicit_elf_is_authoritative(repo, monkeypatch, tmp_path) -> None:
    done = fake_build(monkeypatch, {"fluxdrive-pil.elf": repo / pil.ELF_RELPATH})
    with pytest.raises(FluxdriveError, match="PIL image not found"):
        pil.locate_elf(str(tmp_path / "nope.elf"))
    monkeypatch.setenv(pil.ENV_ELF, str(tmp_path / "env.elf"))
    with pytest.raises(FluxdriveError, match="env.elf"):
        pil.locate_elf(None)
    assert done == []  # never built when a path was given


def test_default_runner_is_built_when_missing(repo, monkeypatch, capsys) -> None:
    runner = repo / sil.SIL_RELPATH
    done = fake_build(monkeypatch, {"fluxdrive-sil": runner})
    assert pil.locate_runner(None) == runner.resolve()
    assert done == [list(a) for a in pil.SIL_BUILD]
    assert done[1] == ["cmake", "--build", "--preset", "host-release", "--target", "fluxdrive-sil"]
    assert "SIL runner missing, building it" in capsys.readouterr().out


def test_explicit_runner_is_authoritative(repo, monkeypatch, tmp_path) -> None:
    done = fake_build(monkeypatch, {"fluxdrive-sil": repo / sil.SIL_RELPATH})
    with pytest.raises(FluxdriveError, match="SIL runner not found"):
        pil.locate_runner(str(tmp_path / "nope"))
    monkeypatch.setenv(sil.ENV_SIL, str(tmp_path / "env-sil"))
    with pytest.raises(FluxdriveError, match="env-sil"):
        pil.locate_runner(None)
    assert done == []


def test_failed_build_is_an_error(repo, monkeypatch) -> None:
    class R:
        returncode = 1

    monkeypatch.setattr(pil.subprocess, "run", lambda argv, cwd=None, check=False: R())
    with pytest.raises(FluxdriveError, match="building the SIL runner failed"):
        pil.locate_runner(None)


def test_qemu_gets_absolute_paths(tmp_path, monkeypatch) -> None:
    """QEMU runs in the work directory: the FIFO and image paths it gets must
    not be relative to the caller's cwd (README on a fresh clone)."""
    monkeypatch.chdir(tmp_path)
    seen = {}

    class P:
        returncode = 0

        def communicate(self, timeout=None):
            return b"", b""

    def popen(argv, cwd=None, **kw):
        seen["argv"], seen["cwd"] = argv, cwd
        (Path(cwd) / "pil_out.bin").write_bytes(b"")
        return P()

    def run(argv, cwd=None, **kw):
        seen["run_argv"], seen["run_cwd"] = argv, cwd
        (Path(cwd) / "pil_out.bin").write_bytes(b"")
        return P()

    monkeypatch.setattr(pil.subprocess, "Popen", popen)
    monkeypatch.setattr(pil.subprocess, "run", run)
    monkeypatch.setattr(pil.threading.Thread, "start", lambda self: None)
    monkeypatch.setattr(pil.threading.Thread, "join", lambda self, timeout=None: None)
    (tmp_path / "out" / "w").mkdir(parents=True)
    pil.run_qemu_trace(Path("x.elf"), Path("out/w"), 1.0, tab={})
    argv = seen["argv"]
    assert Path(seen["cwd"]) == tmp_path / "out" / "w"
    assert Path(argv[argv.index("-D") + 1]) == tmp_path / "out" / "w" / "trace.fifo"
    assert Path(argv[argv.index("-kernel") + 1]) == tmp_path / "x.elf"
    pil.run_qemu(Path("x.elf"), Path("out/w"), 1.0)
    assert Path(seen["run_cwd"]) == tmp_path / "out" / "w"
    assert Path(seen["run_argv"][seen["run_argv"].index("-kernel") + 1]) == tmp_path / "x.elf"


def test_isrs_all() -> None:
    assert _isrs("all") == 0 and _isrs("ALL") == 0 and _isrs("0") == 0 and _isrs("3000") == 3000
    for bad in ("-1", "many"):
        with pytest.raises(argparse.ArgumentTypeError):
            _isrs(bad)
    a = build_parser().parse_args(["pil", "s.json", "--isrs", "all", "--check-cycles", "50"])
    assert a.isrs == 0 and a.check_cycles == 50.0
    assert build_parser().parse_args(["pil", "s.json"]).isrs == 3000
    assert pil.traced_text(0, 6399) == "all 6399 ISRs traced"
    assert pil.traced_text(3000, 3999) == "first 3000 of 3999 ISRs traced"


def run_with(law: str, worst: int, cycles: int) -> pil.PilRun:
    c = pil.Counts(isrs=10, mean=worst - 100, worst=worst, worst_isr=7, blocks={}, funcs={},
                   cycles_mean=cycles - 200, cycles_worst=cycles, cycles_worst_isr=8)
    return pil.PilRun("scen", law, pil.Agreement(100, 0.0, 0, 0, 0, 0, 0), c, True)


def test_checks_on_db_dfvc(capsys) -> None:
    lim = 0.5 * cm.BUDGET_CYCLES  # 5312.5
    assert pil.check_runs([run_with("db_dfvc", 2999, 5312)], 3000, 50) == 0
    assert "= 50.0 % of 10625, limit 50 % (5312)" in capsys.readouterr().out
    assert pil.check_runs([run_with("db_dfvc", 3000, 5312)], 3000, 50) == 1
    assert pil.check_runs([run_with("db_dfvc", 2000, int(lim) + 1)], 3000, 50) == 1
    assert "FAIL: scen/db_dfvc: worst case 5313 estimated cycles" in capsys.readouterr().out
    # other laws are reported for agreement only
    assert pil.check_runs([run_with("foc", 9000, 9000)], 3000, 50) == 0
    # every law's mean and worst case (issue 24, point 8)
    assert pil.check_runs([run_with("foc", 2299, 9000)], None, None, 2200, worst_all=2300) == 0
    assert pil.check_runs([run_with("foc", 2300, 9000)], None, None, 2201, worst_all=2300) == 1
    assert "FAIL: scen/foc: worst case 2300 instructions (ISR 7), limit 2300" in \
        capsys.readouterr().out
    assert pil.check_runs([run_with("pi_dfvc", 2100, 9000)], None, None, 2000) == 1
    a = build_parser().parse_args(["pil", "s.json", "--check-worst-all", "2300"])
    assert a.check_worst_all == 2300
    bad = run_with("foc", 1, 1)
    bad.agreement.duty_bad = 1
    assert pil.check_runs([bad], None, None) == 1


def test_budget_from_the_scenario_period(tmp_path, capsys) -> None:
    """The cycle budget is 170 MHz over the scenario's inverter.pwm_frequency
    (issue 24: the 32 kHz build of DB-DFVC), 16 kHz when not given."""
    assert pil.budget_cycles(16000) == pil.BUDGET_CYCLES == 10625
    assert pil.budget_cycles(32000) == 5312
    sc = tmp_path / "s.json"
    sc.write_text('{"inverter": {"pwm_frequency": 32000}}')
    assert pil.scenario_pwm_hz(sc) == 32000.0
    sc.write_text("{}")
    assert pil.scenario_pwm_hz(sc) == 16000.0
    r = run_with("db_dfvc", 2500, 4249)
    r.budget = 5312
    assert pil.check_runs([r], None, 80) == 0
    assert "= 80.0 % of 5312, limit 80 % (4250)" in capsys.readouterr().out  # 4249.6
    r.counts.cycles_worst = 4250
    assert pil.check_runs([r], None, 80) == 1


def test_pil_help_documents_all(capsys) -> None:
    with pytest.raises(SystemExit):
        build_parser().parse_args(["pil", "--help"])
    text = capsys.readouterr().out
    assert "all or 0: the whole run" in " ".join(text.split())


def test_functions_listed_on_request() -> None:
    r = run_with("db_dfvc", 2000, 4000)
    r.counts.funcs = {"drive_isr": 460.0, "dfvc_step": 293.0}
    r.counts.func_cycles = {"drive_isr": 672.0, "dfvc_step": 493.0}
    assert "function" not in pil.format_report([r], 3000)
    text = pil.format_report([r], 3000, functions=True)
    lines = text.splitlines()
    k = next(i for i, line in enumerate(lines) if line.endswith("function"))
    assert lines[k + 1].split()[-1] == "drive_isr" and "672.0" in lines[k + 1]
    assert lines[k + 2].split()[-1] == "dfvc_step"
    assert build_parser().parse_args(["pil", "s.json", "--functions"]).functions


def test_procs_grouped_by_the_host_procedure(capsys) -> None:
    """--procs (issue 25: each procedure's ISR cost): an ISR belongs to the
    procedure in force before it, or, when none was, to the one after it
    (the ISR that took the request); host_proc is read from the input
    record at HOST_PROC_AT; the checks name the procedure."""
    names = ["offset", "align", "hold", "rs"]
    none = len(names)
    tr = pil.TraceResult(counts=[1] * 9)
    # after each ISR: idle, offset (start), offset, rs (offsets done), rs, idle (rs done), idle ...
    after = [none, 0, 0, 3, 3, none, none, 0, none]
    g = pil.proc_isrs(tr, after, names)
    assert g == {"offset": [1, 2, 3, 7, 8], "rs": [4, 5]}
    assert list(g) == ["offset", "rs"]  # in the order they first ran
    rec = pil.np.zeros(3, pil.np.dtype([("in", f"V{pil.IN_SIZE}"), ("out", pil.OUT)]))
    raw = bytearray(rec.tobytes())
    for k, p in enumerate((none, 0, 3)):
        at = k * rec.dtype.itemsize + pil.HOST_PROC_AT
        raw[at:at + 4] = p.to_bytes(4, "little")
    body = pil.np.frombuffer(bytes(raw), rec.dtype)
    assert list(pil.host_procs(body)) == [none, 0, 3]
    r = run_with("foc", 2400, 9000)
    r.proc = "rs"
    assert pil.check_runs([r], None, None, 2000, worst_all=2300) == 1
    out = capsys.readouterr().out
    assert "FAIL: scen/foc/rs: mean 2300 instructions, limit 2000" in out
    assert "rs" in pil.format_proc_table([r], None)
    assert build_parser().parse_args(["pil", "s.json", "--procs"]).procs


def test_proc_limit_parsed() -> None:
    assert pil.parse_proc_limits(["ldq=2000,4600,85"]) == {"ldq": (2000, 4600, 85.0)}
    for bad in ("ldq", "ldq=1,2", "=1,2,3", "ldq=0,1,2"):
        with pytest.raises(ValueError):
            pil.parse_proc_limits([bad])
    a = build_parser().parse_args(["pil", "s.json", "--procs", "--proc-limit", "star=2400,3300,55"])
    assert a.proc_limit == ["star=2400,3300,55"]
