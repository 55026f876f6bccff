"""Signal groups, log loading/validation, units."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import SIGNALS, make_log
from fluxdrive import logs
from fluxdrive.errors import FluxdriveError


def test_parse_groups_semicolons_and_commas():
    assert logs.parse_groups("speed,speed_ref;torque,torque_ref;i_a,i_b,i_c") == [
        ["speed", "speed_ref"],
        ["torque", "torque_ref"],
        ["i_a", "i_b", "i_c"],
    ]


def test_parse_groups_tolerates_whitespace_and_empty_items():
    assert logs.parse_groups(" speed , speed_ref ;; torque,; ") == [["speed", "speed_ref"], ["torque"]]


def test_parse_groups_comma_only_is_one_subplot():
    assert logs.parse_groups("speed,torque,i_a") == [["speed", "torque", "i_a"]]


@pytest.mark.parametrize("spec", [None, "", "   "])
def test_parse_groups_default(spec):
    assert logs.parse_groups(spec) == logs.DEFAULT_GROUPS
    assert logs.format_groups(logs.parse_groups(spec)) == "speed,speed_ref;torque,torque_ref;i_a,i_b,i_c"


def test_parse_groups_only_separators_is_an_error():
    with pytest.raises(FluxdriveError, match="no signal names"):
        logs.parse_groups(";,;")


def test_load_log_roundtrip(log_file):
    log = logs.load_log(log_file)
    assert logs.signal_names(log) == SIGNALS
    assert log.ndim == 1 and log["t"].dtype == np.dtype("<f8")


def test_unknown_signal_error_lists_available():
    log = make_log(names=["t", "speed", "torque"])
    with pytest.raises(FluxdriveError) as exc:
        logs.check_signals(log, [["speed", "sped"], ["torq"]])
    msg = exc.value.message
    assert "unknown signals: sped, torq" in msg
    assert "available signals: t, speed, torque" in msg


@pytest.mark.parametrize(
    "payload, match",
    [
        (np.arange(10.0), "not a structured array"),
        (np.zeros((2, 3), dtype=[("t", "<f8")]), "1-D"),
        (np.zeros(4, dtype=[("speed", "<f8")]), "no time signal 't'"),
        (np.zeros(4, dtype=[("t", "<f8"), ("v", "<f8", (3,))]), "not a numeric scalar"),
    ],
)
def test_load_log_rejects_bad_arrays(tmp_path, payload, match):
    path = tmp_path / "bad.npy"
    np.save(path, payload)
    with pytest.raises(FluxdriveError, match=match):
        logs.load_log(path)


def test_load_log_missing_and_garbage(tmp_path):
    with pytest.raises(FluxdriveError, match="not found"):
        logs.load_log(tmp_path / "nope.npy")
    junk = tmp_path / "junk.npy"
    junk.write_bytes(b"not an npy file at all")
    with pytest.raises(FluxdriveError, match="cannot read"):
        logs.load_log(junk)


def test_time_window():
    log = make_log(n=1600)  # 0 .. 0.1 s
    win = logs.time_window(log, 0.025, 0.05)
    assert win["t"].min() >= 0.025 and win["t"].max() <= 0.05
    assert len(logs.time_window(log, None, None)) == 1600
    with pytest.raises(FluxdriveError, match="no samples"):
        logs.time_window(log, 5.0, 6.0)
    with pytest.raises(FluxdriveError, match="before"):
        logs.time_window(log, 0.05, 0.01)


def test_units_cover_contract_signals():
    missing = [s for s in SIGNALS if s not in logs.UNITS]
    assert not missing
    assert logs.label_of("speed") == "speed [rad/s]"
    assert logs.label_of("torque") == "torque [N m]"
    assert logs.label_of("duty_a") == "duty_a"
