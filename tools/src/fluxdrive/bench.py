"""Benchmark: run ``fluxdrive-sil SCENARIO --bench`` several times."""

from __future__ import annotations

import re
import statistics
from dataclasses import dataclass
from pathlib import Path

from fluxdrive.errors import FluxdriveError
from fluxdrive.sil import SilResult, build_argv, run_sil

_RTF = re.compile(r"real[- ]time factor\s*:\s*([-+0-9.eE]+|inf|nan)", re.IGNORECASE)
_STEPS = re.compile(r"^\s*steps\s*:\s*(\d+)", re.IGNORECASE | re.MULTILINE)
_WALL = re.compile(r"^\s*wall\s*:\s*([-+0-9.eE]+)\s*s?\b", re.IGNORECASE | re.MULTILINE)


@dataclass
class BenchRun:
    rtf: float
    steps: int | None
    wall: float | None


@dataclass
class BenchReport:
    runs: list[BenchRun]

    @property
    def best(self) -> float:
        return max(r.rtf for r in self.runs)

    @property
    def median(self) -> float:
        return statistics.median(r.rtf for r in self.runs)


def parse_bench_output(text: str) -> BenchRun:
    """Parse ``real-time factor: X``, ``steps: N``, ``wall: S s`` lines."""
    m = _RTF.search(text)
    if not m:
        raise FluxdriveError(
            "SIL runner --bench output has no 'real-time factor: X' line:\n" + text.strip(),
            exit_code=1,
        )
    rtf = float(m.group(1))
    steps = _STEPS.search(text)
    wall = _WALL.search(text)
    return BenchRun(
        rtf=rtf,
        steps=int(steps.group(1)) if steps else None,
        wall=float(wall.group(1)) if wall else None,
    )


def bench_once(sil: Path, scenario: Path, timeout: float | None = None) -> tuple[SilResult, BenchRun | None]:
    result = run_sil(build_argv(sil, scenario, bench=True), timeout=timeout)
    if not result.ok:
        return result, None
    return result, parse_bench_output(result.stdout)


def format_run(i: int, run: BenchRun) -> str:
    parts = [f"run {i}: real-time factor {run.rtf:.1f}"]
    if run.steps is not None:
        parts.append(f"steps {run.steps}")
    if run.wall is not None:
        parts.append(f"wall {run.wall:.3f} s")
    return ", ".join(parts)


def format_report(report: BenchReport) -> str:
    return (
        f"best real-time factor:   {report.best:.1f}\n"
        f"median real-time factor: {report.median:.1f}  ({len(report.runs)} runs)"
    )
