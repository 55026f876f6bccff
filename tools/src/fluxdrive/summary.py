"""Reading and pretty-printing SIL summary JSON (metrics)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from fluxdrive.errors import FluxdriveError


def load_summary(path: str | Path) -> dict[str, Any]:
    p = Path(path)
    if not p.is_file():
        raise FluxdriveError(f"summary file not found: {p}")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise FluxdriveError(f"cannot read {p}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise FluxdriveError(f"{p} is not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise FluxdriveError(f"{p}: expected a JSON object, got {type(data).__name__}")
    return data


def flatten(data: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """Nested objects become dotted keys: {"a": {"b": 1}} -> [("a.b", 1)]."""
    rows: list[tuple[str, Any]] = []
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and value:
            rows.extend(flatten(value, name + "."))
        else:
            rows.append((name, value))
    return rows


def format_value(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, float):
        if math.isfinite(value) and value != 0 and (abs(value) >= 1e6 or abs(value) < 1e-3):
            return f"{value:.4e}"
        return f"{value:.6g}"
    if isinstance(value, list):
        if len(value) <= 8 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            return "[" + ", ".join(format_value(v) for v in value) + "]"
        return json.dumps(value)
    return str(value)


def format_summary(data: dict[str, Any], title: str | None = None) -> str:
    """A two-column, aligned table of the metrics."""
    rows = flatten(data)
    lines = []
    if title:
        lines += [title, "=" * len(title)]
    if not rows:
        lines.append("(empty summary)")
        return "\n".join(lines)
    width = max(len(k) for k, _ in rows)
    for key, value in rows:
        lines.append(f"{key.ljust(width)}  {format_value(value)}")
    return "\n".join(lines)
