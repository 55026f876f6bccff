"""Locating and running the ``fluxdrive-sil`` binary.

Runner contract::

    fluxdrive-sil SCENARIO.json [--log PATH.npy] [--summary PATH.json]
                  [--decimate N] [--bench]

stdout ends with the summary JSON object; errors go to stderr with a non-zero
exit code (2 for a bad scenario).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

from fluxdrive.errors import FluxdriveError

ENV_SIL = "FLUXDRIVE_SIL"
SIL_RELPATH = Path("build/host-release/sil/fluxdrive-sil")
BUILD_HINT = "build it with: cmake --preset host-release && cmake --build build/host-release"


def _is_repo_root(p: Path) -> bool:
    return (p / "CMakePresets.json").is_file() and (p / "sil").is_dir()


def find_repo_root(start: Path | None = None) -> Path | None:
    """The fluxdrive repo root: search upward from *start* (default cwd),
    then upward from this package's location (editable install in tools/)."""
    starts = [Path(start) if start else Path.cwd(), Path(__file__).resolve().parent]
    for s in starts:
        s = s.resolve()
        for p in (s, *s.parents):
            if _is_repo_root(p):
                return p
    return None


def locate_sil(explicit: str | os.PathLike | None = None) -> Path:
    """Path of the runner: *explicit* (--sil), else $FLUXDRIVE_SIL, else
    ``build/host-release/sil/fluxdrive-sil`` under the repo root."""
    if explicit:
        return _check_executable(Path(explicit), "--sil")
    env = os.environ.get(ENV_SIL)
    if env:
        return _check_executable(Path(env), f"${ENV_SIL}")
    root = find_repo_root()
    if root is None:
        raise FluxdriveError(
            "cannot find the fluxdrive repo root (no CMakePresets.json found upward "
            f"from {Path.cwd()}); pass --sil PATH or set {ENV_SIL}",
            hint=BUILD_HINT,
        )
    return _check_executable(root / SIL_RELPATH, "default location")


def _check_executable(p: Path, origin: str) -> Path:
    if not p.exists():
        raise FluxdriveError(f"SIL runner not found ({origin}): {p}", hint=BUILD_HINT)
    if p.is_dir():
        raise FluxdriveError(f"SIL runner path is a directory ({origin}): {p}")
    if not os.access(p, os.X_OK):
        raise FluxdriveError(f"SIL runner is not executable ({origin}): {p}")
    return p.resolve()


@dataclass
class SilResult:
    returncode: int
    stdout: str
    stderr: str
    argv: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.returncode == 0


def build_argv(
    sil: Path,
    scenario: Path,
    log: Path | None = None,
    summary: Path | None = None,
    decimate: int | None = None,
    bench: bool = False,
) -> list[str]:
    argv = [str(sil), str(scenario)]
    if log is not None:
        argv += ["--log", str(log)]
    if summary is not None:
        argv += ["--summary", str(summary)]
    if decimate is not None:
        argv += ["--decimate", str(decimate)]
    if bench:
        argv.append("--bench")
    return argv


def run_sil(argv: list[str], timeout: float | None = None) -> SilResult:
    """Run the binary, capturing stdout and stderr."""
    try:
        proc = subprocess.run(
            argv, capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL
        )
    except FileNotFoundError:
        raise FluxdriveError(f"SIL runner not found: {argv[0]}", hint=BUILD_HINT) from None
    except PermissionError:
        raise FluxdriveError(f"SIL runner is not executable: {argv[0]}") from None
    except OSError as exc:
        raise FluxdriveError(f"cannot start SIL runner {argv[0]}: {exc}") from None
    except subprocess.TimeoutExpired:
        raise FluxdriveError(f"SIL runner timed out after {timeout} s", exit_code=1) from None
    return SilResult(proc.returncode, proc.stdout, proc.stderr, argv)


def relay_stderr(result: SilResult) -> None:
    """Pass the runner's stderr through to ours."""
    if result.stderr:
        sys.stderr.write(result.stderr)
        if not result.stderr.endswith("\n"):
            sys.stderr.write("\n")
        sys.stderr.flush()


def parse_summary_stdout(text: str) -> dict | None:
    """The last JSON object printed on stdout (the runner ends with it), or None.

    The object may span several lines; other lines may precede it.
    """
    decoder = json.JSONDecoder()
    found: dict | None = None
    lines = text.splitlines(keepends=True)
    offsets = []
    pos = 0
    for line in lines:
        if line.lstrip().startswith("{"):
            offsets.append(pos + (len(line) - len(line.lstrip())))
        pos += len(line)
    for off in offsets:
        try:
            obj, end = decoder.raw_decode(text, off)
        except json.JSONDecodeError:
            continue
        if isinstance(obj, dict):
            found = obj
    return found


def scenario_name(scenario: Path) -> str:
    """Display name: the scenario's "name" field when readable, else the file stem."""
    try:
        with open(scenario, encoding="utf-8") as fh:
            data = json.load(fh)
        name = data.get("name") if isinstance(data, dict) else None
        if isinstance(name, str) and name.strip():
            return name.strip()
    except (OSError, ValueError):
        pass
    return scenario.stem
