"""The signal tables (firmware/app/drive_signal_table.h, the laws' and
position sources' hooks, sil/runner/sil_signal_table.h) against everything
made from them: the log's header, docs/log-format.md, the DBC, the tools'
signal table and the PIL stream's field list (issue 24, point 3). Each
generated file edited by hand is caught."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

from conftest import REAL_SIL, REPO_ROOT
from fluxdrive import pil, signals


@pytest.fixture(scope="module")
def table() -> dict:
    if not REAL_SIL.is_file():
        pytest.skip(f"real runner not built ({REAL_SIL} missing)")
    return signals.from_sil(REAL_SIL)


def test_generated_files_agree(table):
    assert signals.problems(REPO_ROOT, table) == []
    for path, text in signals.targets(REPO_ROOT, table).items():
        assert path.read_text(encoding="utf-8") == text, \
            f"{path.relative_to(REPO_ROOT)} differs: fluxdrive signals --write"
    assert signals.table() == table


def test_log_header_is_the_table(table, tmp_path):
    log = tmp_path / "log.npy"
    subprocess.run([str(REAL_SIL), str(REPO_ROOT / "sil/scenarios/pil_ivd_kf_rls.json"),
                    "--log", str(log), "--summary", str(tmp_path / "s.json")],
                   check=True, capture_output=True, timeout=300)
    data = np.load(log)
    assert list(data.dtype.names) == [r["name"] for r in table["log"]]
    # a source's signals hold values while it is in force, a law's are 0
    # while another law runs
    assert np.any(data["dfc_k0"] != 0) and np.any(data["kf_r"] != 0)
    assert np.all(data["flux_mtpa"] == 0)


def test_pil_fields_are_signals(table):
    names = [r["name"] for r in table["log"]]
    assert [f["name"] for f in table["pil_out"]] == list(pil.OUT.names)
    assert all(f["name"] in names for f in table["pil_out"])
    assert pil.OUT.itemsize == 24  # sizeof(isr_stream_out_t)


def test_hand_edits_are_caught(table):
    doc = (REPO_ROOT / signals.DOC_REL).read_text(encoding="utf-8")
    edited = doc.replace("| `speed_est` | rad/s |", "| `speed_est` | rpm |")
    assert edited != doc and signals.render_doc(edited, table) == doc
    dbc = (REPO_ROOT / signals.DBC_REL).read_text(encoding="utf-8")
    edited = dbc.replace('CM_ SG_ 784 torque_est "', 'CM_ SG_ 784 torque_est "edited ')
    assert edited != dbc and signals.render_dbc(edited, table) == dbc
    # a unit changed in the DBC, a telemetry signal without a row
    assert signals.check_dbc(dbc.replace('(0.0001,0) [-214748.3648|214748.3647] "N m" HOST',
                                         '(0.0001,0) [-214748.3648|214748.3647] "Nm" HOST', 1),
                             table)
    extra = dbc.replace(" SG_ rls_ok : 48|1@1+ (1,0) [0|1] \"\" HOST",
                        " SG_ rls_ok : 48|1@1+ (1,0) [0|1] \"\" HOST\n"
                        " SG_ spare : 49|1@1+ (1,0) [0|1] \"\" HOST")
    assert extra != dbc and any("spare" in e for e in signals.check_dbc(extra, table))
    # the tools' table
    t = json.loads(json.dumps(table))
    t["pil_out"][0]["name"] = "duty_x"
    assert signals.render_table(t) != (REPO_ROOT / signals.TABLE_REL).read_text(encoding="utf-8")
