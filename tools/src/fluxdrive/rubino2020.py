"""Rubino et al. 2020 (deadbeat DFVC of SPM drives) reproduced in SIL.

`fluxdrive rubino2020` runs the scenarios sil/scenarios/rubino_*.json,
computes the figures the paper reports, draws one plot per experiment and
writes docs/results-rubino2020.md (a table "paper vs fluxdrive"). The same
functions back the acceptance tests (tests/python/test_rubino2020.py).

All signals are the plant's true values at the sampling instants (log
format: docs/log-format.md) unless named *_ref / *_est.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import json
from pathlib import Path
import subprocess

import numpy as np

from . import capability as capmod

RPM = np.pi / 30.0
SCENARIOS = {
    "step_db": "rubino_torque_step_db.json",
    "step_pi": "rubino_torque_step_pi.json",
    "reversal": "rubino_torque_reversal.json",
    "fw": "rubino_fw_ramp.json",
    "fw_ls120": "rubino_fw_ramp_ls120.json",
    "fw_lm080": "rubino_fw_ramp_lm080.json",
    "bw_db": "rubino_bandwidth_db.json",
    "bw_pi": "rubino_bandwidth_pi.json",
    "speed": "rubino_speed_control.json",
}


@dataclass
class Run:
    scenario: Path
    log: np.ndarray
    summary: dict
    config: dict


def run(sil: Path, scenario: Path, out: Path) -> Run:
    out.mkdir(parents=True, exist_ok=True)
    log_path = out / (scenario.stem + ".npy")
    res = subprocess.run([str(sil), str(scenario), "--log", str(log_path)],
                         capture_output=True, text=True, timeout=600)
    if res.returncode != 0:
        raise RuntimeError(f"{scenario}: fluxdrive-sil exit {res.returncode}: {res.stderr.strip()}")
    cfg = subprocess.run([str(sil), str(scenario), "--print-config"], capture_output=True,
                         text=True, check=True)
    return Run(scenario, np.load(log_path), json.loads(res.stdout), json.loads(cfg.stdout))


# ----------------------------------------------------------------- metrics
def samples_to_band(x: np.ndarray, ref: np.ndarray, k0: int, band: np.ndarray | float,
                    horizon: int) -> int:
    """Samples after k0 until |x - ref| <= band holds for the rest of the
    horizon (k0 is the first ISR that sees the new reference)."""
    sl = slice(k0, k0 + horizon)
    band = band[sl] if isinstance(band, np.ndarray) else band
    err = np.abs(x[sl] - ref[sl]) > band
    bad = np.flatnonzero(err)
    return int(bad[-1] + 1) if bad.size else 0


@dataclass
class StepMetrics:
    n_ref: int  # samples until torque and i_qs within 2 % of their references
    n_step: int  # samples until the torque is within 5 % of the step of its final value
    overshoot: float  # (max torque - final ref) / final ref
    flux_dev: float  # largest |flux - flux before| / flux before, after the step


def step_metrics(log: np.ndarray, t_step: float, horizon: int = 160) -> StepMetrics:
    k0 = int(np.searchsorted(log["t"], t_step - 1e-9))
    t_ref, i_ref = log["torque_ref"], log["i_qs_ref"]
    final = t_ref[k0 + 1]
    n_t = samples_to_band(log["torque"], t_ref, k0, 0.02 * np.abs(t_ref), horizon)
    n_i = samples_to_band(log["i_qs"], i_ref, k0, 0.02 * np.abs(i_ref), horizon)
    # settling of the transient: within 5 % of the step around the final
    # value (the paper's 1 vs 11 samples); needs the ripple below that band
    step = final - t_ref[k0 - 1]
    final_true = np.full_like(t_ref, np.mean(log["torque"][k0 + horizon // 2:k0 + horizon]))
    n_step = samples_to_band(log["torque"], final_true, k0, 0.05 * abs(step), horizon)
    seg = log["torque"][k0:k0 + horizon]
    over = (seg.max() - final) / abs(final) if final > 0 else (final - seg.min()) / abs(final)
    flux0 = np.mean(log["flux"][k0 - 32:k0])
    flux_dev = float(np.max(np.abs(log["flux"][k0:k0 + horizon] - flux0)) / flux0)
    return StepMetrics(max(n_t, n_i), n_step, float(over), flux_dev)


@dataclass
class SineMetrics:
    ratio: float  # amplitude of the true torque's 1.5 kHz part / the reference's
    lag: float  # [samples]


def sine_metrics(log: np.ndarray, t0: float, freq: float) -> SineMetrics:
    m = log["t"] >= t0
    t = log["t"][m]
    basis = np.column_stack([np.sin(2 * np.pi * freq * t), np.cos(2 * np.pi * freq * t),
                             np.ones_like(t)])
    def fit(y):
        c, *_ = np.linalg.lstsq(basis, y, rcond=None)
        return complex(c[0], c[1])
    r, y = fit(log["torque_ref"][m]), fit(log["torque"][m])
    ts = float(np.median(np.diff(t)))
    lag = ((np.angle(r) - np.angle(y)) % (2 * np.pi)) / (2 * np.pi * freq * ts)
    return SineMetrics(abs(y) / abs(r), float(lag))


@dataclass
class RampMetrics:
    worst_ratio: float  # min over speed of torque / capability
    worst_ratio_rpm: float
    delta_max_deg: float  # largest true load angle
    current_max: float  # largest true |i_dq| at the sampling instants
    fw_ratio: float  # flux at base speed / flux at top speed
    base_rpm: float  # base speed (model)
    mtpv_rpm: float  # MTPV entry (model)
    sil_mtpv_rpm: float  # first speed where the true load angle reaches delta_max - 1 deg
    power_top: float  # mean power over 1000-1200 rpm [W]
    faults: list = field(default_factory=list)
    cap_rpm: np.ndarray | None = None
    cap_torque: np.ndarray | None = None


def ramp_metrics(r: Run, smooth: int = 8) -> RampMetrics:
    log = r.log
    m, lim = capmod.from_config(r.config)
    # true machine for the capability: the plant's parameters (detuned runs
    # are compared with what the real machine allows)
    # the torque averaged over `smooth` log rows (ripple), edges excluded
    kernel = np.ones(smooth) / smooth
    avg = np.convolve(log["torque"], kernel, mode="same")
    on = (log["t"] > 0.12) & (log["speed"] > 100.5 * RPM)
    on[:smooth] = False
    on[-smooth:] = False
    speed = log["speed"][on]
    torque = avg[on]
    cap = capmod.capability(m, lim, speed, n_id=1501)
    ratio = torque / np.maximum(cap.torque, 1e-9)
    k = int(np.argmin(ratio))
    flux = log["flux"][on]
    corners = capmod.corner_speeds(capmod.capability(m, lim, np.linspace(100, 1200, 221) * RPM), m, lim)
    base = corners["base_speed"]
    flux_base = float(np.interp(base, speed, flux))
    delta = np.degrees(log["delta"][on])
    reach = np.flatnonzero(delta >= np.degrees(lim.delta_max) - 1.0)
    top = speed >= 1000 * RPM
    return RampMetrics(
        worst_ratio=float(ratio[k]), worst_ratio_rpm=float(speed[k] / RPM),
        delta_max_deg=float(delta.max()),
        current_max=float(np.max(np.hypot(log["i_d"], log["i_q"])[on])),
        fw_ratio=float(flux_base / np.mean(flux[speed >= 1190 * RPM])),
        base_rpm=base / RPM, mtpv_rpm=corners["mtpv_speed"] / RPM,
        sil_mtpv_rpm=float(speed[reach[0]] / RPM) if reach.size else float("nan"),
        power_top=float(np.mean((torque * speed)[top])),
        faults=list(r.summary.get("faults_seen", [])),
        cap_rpm=speed / RPM, cap_torque=cap.torque)


@dataclass
class SpeedMetrics:
    overshoot: float
    t_reach: float  # first time within 1 % of 1200 rpm [s]
    faults: list


def speed_metrics(r: Run, target_rpm: float = 1200.0) -> SpeedMetrics:
    w = r.log["speed"] / RPM
    reach = np.flatnonzero(np.abs(w - target_rpm) <= 0.01 * target_rpm)
    return SpeedMetrics(float((w.max() - target_rpm) / target_rpm),
                        float(r.log["t"][reach[0]]) if reach.size else float("nan"),
                        list(r.summary.get("faults_seen", [])))


# ------------------------------------------------------------------- plots
def _fig(rows: int, title: str):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(rows, 1, figsize=(8, 2.2 * rows), sharex=True)
    fig.suptitle(title, fontsize=10)
    return plt, fig, np.atleast_1d(ax)


def plot_steps(runs: dict, keys: list, t_step: float, path: Path, title: str) -> None:
    plt, fig, ax = _fig(3, title)
    for key in keys:
        log = runs[key].log
        m = (log["t"] > t_step - 0.0015) & (log["t"] < t_step + 0.004)
        n = (log["t"][m] - t_step) / 62.5e-6
        tag = runs[key].summary["law"].upper().replace("_", "-")
        ax[0].step(n, log["torque"][m], where="post", label=f"torque {tag}")
        ax[1].step(n, log["i_qs"][m], where="post", label=f"i_qs {tag}")
        ax[2].step(n, log["flux"][m] * 1e3, where="post", label=f"flux {tag}")
    log = runs[keys[0]].log
    m = (log["t"] > t_step - 0.0015) & (log["t"] < t_step + 0.004)
    n = (log["t"][m] - t_step) / 62.5e-6
    ax[0].step(n, log["torque_ref"][m], "k--", where="post", label="reference")
    ax[1].step(n, log["i_qs_ref"][m], "k--", where="post", label="reference")
    ax[0].set_ylabel("N m"), ax[1].set_ylabel("A"), ax[2].set_ylabel("mVs")
    ax[2].set_xlabel("samples after the step (Ts = 62.5 us)")
    for a in ax:
        a.grid(True, alpha=0.3), a.legend(fontsize=7, loc="best")
    fig.tight_layout(), fig.savefig(path, dpi=110), plt.close(fig)


def plot_ramp(runs: dict, metrics: dict, path: Path) -> None:
    plt, fig, ax = _fig(4, "Rubino 2020 Figs. 14, 19, 20: rated torque, 100 -> 1200 rpm at 400 rpm/s")
    for key, label in [("fw", "nominal"), ("fw_ls120", "L_s x1.2"), ("fw_lm080", "lambda_m x0.8")]:
        log = runs[key].log
        rpm = log["speed"] / RPM
        m = log["t"] > 0.12
        ax[0].plot(rpm[m], log["torque"][m], lw=0.8, label=label)
        ax[1].plot(rpm[m], (log["torque"] * log["speed"])[m], lw=0.8, label=label)
        ax[2].plot(rpm[m], log["flux"][m] * 1e3, lw=0.8, label=label)
        ax[3].plot(rpm[m], np.degrees(log["delta"][m]), lw=0.8, label=label)
    mt = metrics["fw"]
    ax[0].plot(mt.cap_rpm, mt.cap_torque, "k--", lw=1, label="model capability")
    ax[0].plot(mt.cap_rpm, 0.9 * mt.cap_torque, "k:", lw=1, label="90 % of it")
    ax[1].plot(mt.cap_rpm, mt.cap_torque * mt.cap_rpm * RPM, "k--", lw=1, label="model capability")
    ax[3].axhline(80, color="k", ls="--", lw=1, label="delta_max")
    for a, y in zip(ax, ["torque N m", "power W", "flux mVs", "load angle deg"]):
        a.set_ylabel(y), a.grid(True, alpha=0.3), a.legend(fontsize=7, loc="best")
    ax[3].set_xlabel("speed rpm")
    fig.tight_layout(), fig.savefig(path, dpi=110), plt.close(fig)


def plot_sine(runs: dict, path: Path) -> None:
    plt, fig, ax = _fig(2, "Rubino 2020 Figs. 23-24: 10 N m + 0.5 N m at 1.5 kHz, 100 rpm")
    for a, key in zip(ax, ["bw_db", "bw_pi"]):
        log = runs[key].log
        m = (log["t"] > 0.12) & (log["t"] < 0.1233)
        n = np.arange(m.sum())
        a.step(n, log["torque_ref"][m], "k--", where="post", label="reference")
        a.step(n, log["torque"][m], where="post", label="torque (true)")
        a.set_ylabel("N m"), a.grid(True, alpha=0.3), a.legend(fontsize=7)
        a.set_title(runs[key].summary["law"].upper().replace("_", "-"), fontsize=9)
    ax[-1].set_xlabel("samples")
    fig.tight_layout(), fig.savefig(path, dpi=110), plt.close(fig)


def plot_speed(run_: Run, path: Path) -> None:
    plt, fig, ax = _fig(3, "Rubino 2020 Fig. 18: speed control 0 -> 1200 rpm, 1200 rpm/s")
    log = run_.log
    ax[0].plot(log["t"], log["speed"] / RPM, label="speed")
    ax[0].plot(log["t"], log["speed_ref"] / RPM, "k--", label="reference (ramped)")
    ax[1].plot(log["t"], log["torque"], label="torque"), ax[1].plot(log["t"], log["torque_ref"], "k--", label="reference")
    ax[2].plot(log["t"], np.degrees(log["delta"]), label="load angle")
    for a, y in zip(ax, ["rpm", "N m", "deg"]):
        a.set_ylabel(y), a.grid(True, alpha=0.3), a.legend(fontsize=7)
    ax[-1].set_xlabel("s")
    fig.tight_layout(), fig.savefig(path, dpi=110), plt.close(fig)


# ------------------------------------------------------------------- all
def run_all(sil: Path, scenario_dir: Path, out: Path) -> tuple[dict, dict]:
    runs = {k: run(sil, scenario_dir / f, out) for k, f in SCENARIOS.items()}
    met = {
        "step_db": step_metrics(runs["step_db"].log, 0.1),
        "step_pi": step_metrics(runs["step_pi"].log, 0.1),
        "reversal": step_metrics(runs["reversal"].log, 0.1, horizon=400),
        "fw": ramp_metrics(runs["fw"]),
        "fw_ls120": ramp_metrics(runs["fw_ls120"]),
        "fw_lm080": ramp_metrics(runs["fw_lm080"]),
        "bw_db": sine_metrics(runs["bw_db"].log, 0.105, 1500.0),
        "bw_pi": sine_metrics(runs["bw_pi"].log, 0.105, 1500.0),
        "speed": speed_metrics(runs["speed"]),
    }
    return runs, met


def report(met: dict) -> str:
    s_db, s_pi, rv = met["step_db"], met["step_pi"], met["reversal"]
    fw, ls, lm = met["fw"], met["fw_ls120"], met["fw_lm080"]
    loss = lambda d: 100.0 * (1.0 - d.power_top / fw.power_top)  # noqa: E731
    rows = [
        ("Torque step 10 -> 11 N m, 100 rpm (Figs. 21-22)", "", ""),
        ("samples to within 2 % of the references (torque and i_qs), DB", "1", f"{s_db.n_ref}"),
        ("same, PI-DFVC", "11", f"{s_pi.n_ref}"),
        ("samples to settle within 5 % of the step, DB / PI", "1 / 11", f"{s_db.n_step} / {s_pi.n_step}"),
        ("overshoot DB", "none", f"{100 * s_db.overshoot:.2f} %"),
        ("Torque reversal -20 -> +20 N m, 100 rpm (Figs. 12-13)", "", ""),
        ("overshoot", "none", f"{100 * rv.overshoot:.2f} %"),
        ("largest flux deviation", "flux unchanged", f"{100 * rv.flux_dev:.2f} %"),
        ("Rated torque, 100 -> 1200 rpm at 400 rpm/s (Fig. 14)", "", ""),
        ("power held at high speed (mean 1000-1200 rpm)", "about 600 W", f"{fw.power_top:.0f} W"),
        ("base speed (model)", "about 240 rpm", f"{fw.base_rpm:.0f} rpm"),
        ("MTPV entry (model / SIL, delta within 1 deg of 80)", "about 300 rpm",
         f"{fw.mtpv_rpm:.0f} / {fw.sil_mtpv_rpm:.0f} rpm"),
        ("flux-weakening ratio (flux at base speed / at 1200 rpm)", "1:5", f"1:{fw.fw_ratio:.1f}"),
        ("worst torque / model capability", "-", f"{100 * fw.worst_ratio:.1f} % at {fw.worst_ratio_rpm:.0f} rpm"),
        ("largest load angle", "80 deg (limited)", f"{fw.delta_max_deg:.1f} deg"),
        ("largest current amplitude (limit 3.54 A)", "limited", f"{fw.current_max:.3f} A"),
        ("Detuning, same ramp (Figs. 19-20)", "", ""),
        ("L_s x1.2: power loss at high speed", "about 17 %", f"{loss(ls):.1f} %, faults: {ls.faults or 'none'}"),
        ("lambda_m x0.8: power loss at high speed", "similar", f"{loss(lm):.1f} %, faults: {lm.faults or 'none'}"),
        ("largest current amplitude L_s x1.2 / lambda_m x0.8", "stable", f"{ls.current_max:.3f} / {lm.current_max:.3f} A"),
        ("Torque bandwidth, 10 + 0.5 N m at 1.5 kHz, 100 rpm (Figs. 23-24)", "", ""),
        ("amplitude ratio / lag, DB", "follows, one-sample shifts", f"{met['bw_db'].ratio:.3f} / {met['bw_db'].lag:.2f} samples"),
        ("amplitude ratio / lag, PI-DFVC", "does not follow", f"{met['bw_pi'].ratio:.3f} / {met['bw_pi'].lag:.2f} samples"),
        ("Speed control 0 -> 1200 rpm, 1200 rpm/s (Fig. 18)", "", ""),
        ("overshoot", "none", f"{100 * met['speed'].overshoot:.2f} %"),
        ("time to within 1 % of 1200 rpm", "about 1 s", f"{met['speed'].t_reach:.3f} s"),
    ]
    out = ["| experiment / figure | paper | fluxdrive |", "|---|---|---|"]
    for a, b, c in rows:
        out.append(f"| **{a}** | | |" if b == "" and c == "" else f"| {a} | {b} | {c} |")
    return "\n".join(out)


def main_rubino(args) -> int:
    from .sil import find_repo_root, locate_sil

    root = find_repo_root() or Path.cwd()
    sil = locate_sil(args.sil)
    out = Path(args.out) if args.out else root / "out" / "rubino2020"
    figs = Path(args.figures) if args.figures else root / "docs" / "figures"
    figs.mkdir(parents=True, exist_ok=True)
    runs, met = run_all(sil, root / "sil" / "scenarios", out)
    plot_steps(runs, ["step_db", "step_pi"], 0.1, figs / "rubino2020_step.png",
               "Rubino 2020 Figs. 21-22: torque step 10 -> 11 N m at 100 rpm")
    plot_steps(runs, ["reversal"], 0.1, figs / "rubino2020_reversal.png",
               "Rubino 2020 Figs. 12-13: torque reversal -20 -> +20 N m at 100 rpm")
    plot_ramp(runs, met, figs / "rubino2020_fw_ramp.png")
    plot_sine(runs, figs / "rubino2020_bandwidth.png")
    plot_speed(runs["speed"], figs / "rubino2020_speed.png")
    table = report(met)
    print(table)
    if args.doc:
        doc = Path(args.doc)
        text = doc.read_text()
        a, b = "<!-- rubino2020-table:begin -->", "<!-- rubino2020-table:end -->"
        if a in text and b in text:
            text = text[:text.index(a) + len(a)] + "\n" + table + "\n" + text[text.index(b):]
            doc.write_text(text)
            print(f"updated {doc}")
    return 0
