"""One end-to-end test against the real fluxdrive-sil, when it has been built."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import DEFAULT_SCENARIO, REAL_SIL, SIGNALS, assert_png
from fluxdrive.cli import main


@pytest.mark.real_sil
def test_real_sil_default_scenario(tmp_path, capsys):
    if not REAL_SIL.is_file():
        pytest.skip(f"real runner not built ({REAL_SIL} missing); "
                    "build it with: cmake --preset host-release && cmake --build build/host-release")
    if not DEFAULT_SCENARIO.is_file():
        pytest.skip(f"no scenario {DEFAULT_SCENARIO.relative_to(DEFAULT_SCENARIO.parents[2])} yet")
    out = tmp_path / "default"
    rc = main(["run", str(DEFAULT_SCENARIO), "--sil", str(REAL_SIL), "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 0, captured.err
    log = np.load(out / "log.npy")
    missing = [s for s in SIGNALS if s not in log.dtype.names]
    assert not missing, f"log lacks signals: {missing}"
    assert log.ndim == 1 and len(log) > 1
    assert all(log.dtype[n] == np.dtype("<f8") for n in log.dtype.names)
    assert np.all(np.diff(log["t"]) > 0)
    assert (out / "summary.json").is_file()
    assert_png(out / "plot.png")


@pytest.mark.real_sil
def test_multibyte_name_cut_by_the_limit_gives_a_readable_summary(tmp_path, capsys):
    """Issue 13, defect 6: a scenario name longer than the runner keeps,
    cut inside a multi-byte character, still gives a summary the tool reads
    (it is JSON: UTF-8)."""
    if not REAL_SIL.is_file():
        pytest.skip("real runner not built")
    import json
    sc = json.loads(DEFAULT_SCENARIO.read_text())
    sc["duration"] = 0.02
    for pad in (94, 95):  # the cut inside the 2-byte and the 3-byte character
        sc["name"] = "x" * pad + "\u00e9\u20ac\U0001f600"
        path = tmp_path / f"name{pad}.json"
        path.write_text(json.dumps(sc, ensure_ascii=False), encoding="utf-8")
        out = tmp_path / f"out{pad}"
        rc = main(["run", str(path), "--sil", str(REAL_SIL), "--out", str(out), "--no-plot"])
        captured = capsys.readouterr()
        assert rc == 0, captured.err
        summary = json.loads((out / "summary.json").read_bytes().decode("utf-8"))
        assert summary["scenario"].startswith("x" * pad)
