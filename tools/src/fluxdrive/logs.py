"""Loading and validating SIL logs (.npy structured arrays), signal groups, units.

A log is a NumPy ``.npy`` file holding a 1-D structured array whose fields are
little-endian float64 signals (``log['t']``, ``log['speed']``, ...).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fluxdrive.errors import FluxdriveError

#: SI unit of each known signal ("" = dimensionless).
UNITS: dict[str, str] = {
    "t": "s",
    "speed": "rad/s",
    "speed_est": "rad/s",
    "speed_ref": "rad/s",
    "torque": "N m",
    "torque_ref": "N m",
    "torque_est": "N m",
    "i_a": "A",
    "i_b": "A",
    "i_c": "A",
    "i_d": "A",
    "i_q": "A",
    "i_qs": "A",
    "i_qs_ref": "A",
    "v_dc": "V",
    "duty_a": "",
    "duty_b": "",
    "duty_c": "",
    "flux": "Wb",
    "flux_ref": "Wb",
    "delta": "rad",
    "theta_e": "rad",
    "state": "",
    "faults": "",
}

#: Signals that hold discrete values and are drawn as steps.
DISCRETE_SIGNALS = frozenset({"state", "faults"})

#: Default plot layout: one subplot per group.
DEFAULT_GROUPS: list[list[str]] = [
    ["speed", "speed_ref"],
    ["torque", "torque_ref"],
    ["i_a", "i_b", "i_c"],
]

TIME = "t"


def unit_of(name: str) -> str:
    """Unit of a signal, '' if dimensionless or unknown."""
    return UNITS.get(name, "")


def label_of(name: str) -> str:
    """Signal name with its unit, e.g. ``speed [rad/s]``."""
    unit = unit_of(name)
    return f"{name} [{unit}]" if unit else name


def parse_groups(spec: str | None) -> list[list[str]]:
    """Parse ``"speed,speed_ref;torque,torque_ref;i_a,i_b,i_c"`` into groups.

    Semicolons separate subplots, commas separate signals within one subplot.
    Whitespace and empty items are ignored. ``None`` or an empty spec gives the
    default groups.
    """
    if spec is None or not spec.strip():
        return [list(g) for g in DEFAULT_GROUPS]
    groups: list[list[str]] = []
    for part in spec.split(";"):
        names = [n.strip() for n in part.split(",") if n.strip()]
        if names:
            groups.append(names)
    if not groups:
        raise FluxdriveError(f"no signal names in --signals {spec!r}")
    return groups


def format_groups(groups: list[list[str]]) -> str:
    """Inverse of :func:`parse_groups`."""
    return ";".join(",".join(g) for g in groups)


def load_log(path: str | Path) -> np.ndarray:
    """Load and validate a SIL log; raise :class:`FluxdriveError` on bad input."""
    p = Path(path)
    if not p.exists():
        raise FluxdriveError(f"log file not found: {p}")
    if p.is_dir():
        raise FluxdriveError(f"log path is a directory, expected a .npy file: {p}")
    try:
        data = np.load(p, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise FluxdriveError(f"cannot read {p} as a NumPy .npy log: {exc}") from None
    if isinstance(data, np.lib.npyio.NpzFile):  # pragma: no cover - .npz given
        data.close()
        raise FluxdriveError(f"{p} is an .npz archive; expected a .npy log")
    return validate_log(data, source=str(p))


def validate_log(data: np.ndarray, source: str = "log") -> np.ndarray:
    """Check that *data* is a 1-D structured array of numeric fields with 't'."""
    if not isinstance(data, np.ndarray) or data.dtype.names is None:
        raise FluxdriveError(f"{source}: not a structured array (no named signals)")
    if data.ndim != 1:
        raise FluxdriveError(f"{source}: expected a 1-D array, got shape {data.shape}")
    for name in data.dtype.names:
        kind = data.dtype.fields[name][0]
        if kind.subdtype is not None or kind.kind not in "fiub":
            raise FluxdriveError(f"{source}: signal {name!r} is not a numeric scalar ({kind})")
    if TIME not in data.dtype.names:
        raise FluxdriveError(
            f"{source}: no time signal 't'; available: {', '.join(data.dtype.names)}"
        )
    return data


def signal_names(log: np.ndarray) -> list[str]:
    return list(log.dtype.names or ())


def check_signals(log: np.ndarray, groups: list[list[str]]) -> None:
    """Raise a clear error naming unknown signals and listing available ones."""
    available = signal_names(log)
    unknown = [n for g in groups for n in g if n not in available]
    if unknown:
        uniq = list(dict.fromkeys(unknown))
        plural = "s" if len(uniq) > 1 else ""
        raise FluxdriveError(
            f"unknown signal{plural}: {', '.join(uniq)}\n"
            f"available signals: {', '.join(available)}"
        )


def time_window(log: np.ndarray, t0: float | None = None, t1: float | None = None) -> np.ndarray:
    """Rows with t0 <= t <= t1 (either bound optional)."""
    if t0 is not None and t1 is not None and t1 < t0:
        raise FluxdriveError(f"--t1 ({t1}) is before --t0 ({t0})")
    t = log[TIME]
    mask = np.ones(t.shape, dtype=bool)
    if t0 is not None:
        mask &= t >= t0
    if t1 is not None:
        mask &= t <= t1
    out = log[mask]
    if out.size == 0:
        span = f"[{t.min():g}, {t.max():g}] s" if t.size else "empty"
        raise FluxdriveError(f"no samples in the time window; the log spans {span}")
    return out
