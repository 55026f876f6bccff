"""The README's PIL command, exactly as printed, on a fresh clone.

README.md lists ``.venv/bin/fluxdrive pil ...``. This test takes that line
from the README (so it fails when the README changes the command and the
tool does not follow), clones the repository (the local one, no network)
into a temporary directory and runs the command there from the clone's
root: nothing is built in the clone and no FLUXDRIVE_* variable points
elsewhere, so ``fluxdrive pil`` must build its own PIL image (preset
cortex-m4f) and SIL runner (preset host-release) and run QEMU with the
default relative ``--out``. The tools are the clone's (``PYTHONPATH`` =
the clone's ``tools/src``, this interpreter standing in for ``.venv``,
which a fresh clone does not have either).

Uncommitted changes to tracked files are applied to the clone (``git diff
HEAD``), so the test checks the tree as it is being worked on; untracked
files are not carried (as in a commit). Slow: a host-release build of
fluxdrive-sil, a cross build of the image and one PIL run, about 1-2 min
on two cores.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import REPO_ROOT

README = REPO_ROOT / "README.md"
TOOLS = ("git", "cmake", "ninja", "arm-none-eabi-gcc", "qemu-system-arm")


def readme_pil_command(text: str) -> str:
    """The one ``fluxdrive pil`` command the README prints (in backticks)."""
    found = re.findall(r"`((?:\S*/)?fluxdrive pil [^`]+)`", text)
    assert len(found) == 1, f"README.md should print one `fluxdrive pil` command, found {found}"
    return found[0]


def test_readme_command_is_found() -> None:
    cmd = readme_pil_command(README.read_text(encoding="utf-8"))
    assert cmd.startswith(".venv/bin/fluxdrive pil sil/scenarios/")
    with pytest.raises(AssertionError):
        readme_pil_command("`fluxdrive pil a.json` and `fluxdrive pil b.json`")


def _git(*args: str, cwd: Path, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True, **kw)


def test_readme_pil_command_on_a_fresh_clone(tmp_path: Path) -> None:
    missing = [t for t in TOOLS if shutil.which(t) is None]
    if missing:
        pytest.skip(f"needs {', '.join(missing)}")
    if subprocess.run(["git", "rev-parse", "--is-inside-work-tree"], cwd=REPO_ROOT,
                      capture_output=True).returncode != 0:
        pytest.skip("not a git checkout: nothing to clone")
    t0 = time.monotonic()
    clone = tmp_path / "fluxdrive"
    head = _git("rev-parse", "HEAD", cwd=REPO_ROOT, text=True).stdout.strip()
    _git("clone", "-q", "--no-checkout", str(REPO_ROOT), str(clone), cwd=tmp_path)
    _git("checkout", "-q", "--detach", head, cwd=clone)
    diff = _git("diff", "HEAD", "--binary", cwd=REPO_ROOT).stdout
    if diff:
        subprocess.run(["git", "apply", "--whitespace=nowarn"], cwd=clone, input=diff,
                       check=True, capture_output=True)
    assert not (clone / "build").exists() and not (clone / ".venv").exists()

    # the command as the README in the clone prints it, run from the clone's root
    cmd = readme_pil_command((clone / "README.md").read_text(encoding="utf-8"))
    assert cmd == readme_pil_command(README.read_text(encoding="utf-8"))
    words = shlex.split(cmd)
    assert Path(words[0]).name == "fluxdrive"
    argv = [sys.executable, "-m", "fluxdrive", *words[1:]]
    env = {k: v for k, v in os.environ.items() if not k.startswith("FLUXDRIVE_")}
    env["PYTHONPATH"] = str(clone / "tools" / "src")
    env["CMAKE_BUILD_PARALLEL_LEVEL"] = "2"  # two shared cores
    env.setdefault("MPLBACKEND", "Agg")
    where = subprocess.run([sys.executable, "-c", "import fluxdrive; print(fluxdrive.__file__)"],
                           cwd=clone, env=env, capture_output=True, text=True, check=True)
    assert Path(where.stdout.strip()).is_relative_to(clone), where.stdout

    r = subprocess.run(argv, cwd=clone, env=env, capture_output=True, text=True, timeout=1200)
    elapsed = time.monotonic() - t0
    out = r.stdout + r.stderr
    print(f"fresh clone + `{cmd}`: {elapsed:.1f} s\n{out[-3000:]}")
    assert r.returncode == 0, f"`{cmd}` failed on a fresh clone (exit {r.returncode}):\n{out}"
    # it built what it needed, in the clone, and said so
    assert "building it: cmake --preset host-release" in out
    assert "building it: cmake --preset cortex-m4f" in out
    assert (clone / "build" / "host-release" / "sil" / "fluxdrive-sil").is_file()
    assert (clone / "build" / "cortex-m4f" / "pil" / "fluxdrive-pil.elf").is_file()
    # the replay agreed with the host build and the traced replay ran
    assert "-> OK" in out and "FAIL" not in out
    assert "traced outputs identical to untraced: True" in out
    scenario = Path(next(w for w in words[2:] if w.endswith(".json"))).stem
    runs = list((clone / "out" / "pil").glob(f"{scenario}-*/pil_out.bin"))
    assert runs, f"no PIL output under {clone / 'out' / 'pil'}"
    assert not list((clone / "out" / "pil").glob("*/trace.fifo"))
