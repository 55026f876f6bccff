"""Checks of a flux map (fluxdrive frame), each with its own message naming
the file, the check and the grid cell. Tolerances:

* regular grid: every step within 1e-6 of the mean step (relative);
* incremental self-inductances l_dd, l_qq > 0 in every cell (the cell's
  mean differences);
* incremental matrix positive definite: the smallest eigenvalue of its
  symmetric part > 0 in every cell (with the grid convex, this makes
  lambda(i) one-to-one: the plant's inverse is unique);
* reciprocity: |l_dq - l_qd| <= RECIPROCITY_TOL sqrt(l_dd l_qq) in every
  cell (a map from a magnetic energy has l_dq = l_qd; measured maps are
  noisy);
* both signs of i_q covered (negative torque, by the map itself), at most
  64 points an axis (the blob), at least 2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import FluxMapError
from .model import FluxMap

RECIPROCITY_TOL = 0.10
REGULAR_TOL = 1e-6
GRID_MAX = 64


def check_axis(file: str, name: str, a: np.ndarray) -> None:
    if a.ndim != 1:
        raise FluxMapError(file, "axis not 1-D", f"{name} has shape {a.shape}")
    if len(a) < 2:
        raise FluxMapError(file, "too few points", f"{name} has {len(a)} point(s), at least 2")
    if len(a) > GRID_MAX:
        raise FluxMapError(file, "grid too large",
                           f"{name} has {len(a)} points, at most {GRID_MAX} (resample it)")
    if not np.all(np.isfinite(a)):
        k = int(np.flatnonzero(~np.isfinite(a))[0])
        raise FluxMapError(file, "axis value not finite", f"{name}[{k}] = {a[k]}")
    d = np.diff(a)
    if not np.all(d > 0):
        k = int(np.flatnonzero(~(d > 0))[0])
        raise FluxMapError(file, "axis not increasing", f"{name}[{k}] = {a[k]:g}, "
                           f"{name}[{k + 1}] = {a[k + 1]:g}")
    step = (a[-1] - a[0]) / (len(a) - 1)
    bad = np.abs(d - step) > REGULAR_TOL * abs(step)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise FluxMapError(file, "irregular grid", f"{name} step {d[k]:g} between points {k} and "
                           f"{k + 1}, mean step {step:g}")


def _where(m: FluxMap, j: int, k: int) -> str:
    return f"cell ({j}, {k}) at i_d = {m.i_d[j]:g} A, i_q = {m.i_q[k]:g} A"


def check_map(file: str, m: FluxMap) -> None:
    """All checks; raises FluxMapError at the first failure."""
    check_axis(file, "i_d", m.i_d)
    check_axis(file, "i_q", m.i_q)
    for name, a in (("psi_d", m.psi_d), ("psi_q", m.psi_q)):
        if a.shape != (m.nq, m.nd):
            raise FluxMapError(file, "wrong shape", f"{name} has shape {a.shape}, the axes give "
                               f"({m.nq}, {m.nd}) (rows: i_q)")
        bad = ~np.isfinite(a)
        if np.any(bad):
            k, j = (int(x[0]) for x in np.nonzero(bad))
            raise FluxMapError(file, "flux not finite", f"point ({j}, {k}) at i_d = "
                               f"{m.i_d[j]:g} A, i_q = {m.i_q[k]:g} A", f"{name} = {a[k, j]}")
    if not (m.i_q[0] < 0 < m.i_q[-1]):
        raise FluxMapError(file, "i_q does not cover both signs",
                           f"i_q from {m.i_q[0]:g} to {m.i_q[-1]:g} A "
                           "(a map of i_q >= 0 only: --mirror)")
    if not (isinstance(m.pole_pairs, (int, np.integer)) and 1 <= m.pole_pairs <= 100):
        raise FluxMapError(file, "pole pairs", f"{m.pole_pairs!r}: an integer 1..100")
    pd, pq = m.psi_d, m.psi_q
    ldd = 0.5 * (pd[:-1, 1:] - pd[:-1, :-1] + pd[1:, 1:] - pd[1:, :-1]) / m.did
    lqd = 0.5 * (pq[:-1, 1:] - pq[:-1, :-1] + pq[1:, 1:] - pq[1:, :-1]) / m.did
    ldq = 0.5 * (pd[1:, :-1] - pd[:-1, :-1] + pd[1:, 1:] - pd[:-1, 1:]) / m.diq
    lqq = 0.5 * (pq[1:, :-1] - pq[:-1, :-1] + pq[1:, 1:] - pq[:-1, 1:]) / m.diq
    for name, l in (("l_dd", ldd), ("l_qq", lqq)):
        bad = ~(l > 0)
        if np.any(bad):
            k, j = (int(x[0]) for x in np.nonzero(bad))
            raise FluxMapError(file, "incremental self-inductance not positive", _where(m, j, k),
                               f"{name} = {l[k, j]:.4g} H")
    c = 0.5 * (ldq + lqd)
    eig = 0.5 * (ldd + lqq) - np.sqrt(0.25 * (ldd - lqq) ** 2 + c * c)
    bad = ~(eig > 0)
    if np.any(bad):
        k, j = (int(x[0]) for x in np.nonzero(bad))
        raise FluxMapError(file, "incremental inductance matrix not positive definite (lambda(i) "
                           "not invertible)", _where(m, j, k),
                           f"l_dd = {ldd[k, j]:.4g}, l_qq = {lqq[k, j]:.4g}, "
                           f"l_dq = {ldq[k, j]:.4g}, l_qd = {lqd[k, j]:.4g} H")
    rec = np.abs(ldq - lqd) / np.sqrt(ldd * lqq)
    bad = rec > RECIPROCITY_TOL
    if np.any(bad):
        k, j = (int(x[0]) for x in np.nonzero(bad))
        raise FluxMapError(file, "not reciprocal", _where(m, j, k),
                           f"|l_dq - l_qd| = {rec[k, j]:.3g} sqrt(l_dd l_qq) > "
                           f"{RECIPROCITY_TOL:g} (l_dq = {ldq[k, j]:.4g}, l_qd = {lqd[k, j]:.4g} H)")


# --- the convention the data show (docs/flux-maps.md, "Checks of the data") ---

PM_FRAC = 0.05  # a PM flux: |lambda(0)| above this fraction of the grid's largest flux
PM_AXIS_DEG = 15.0  # the PM flux within this angle of an axis
SALIENCY = 1.2  # salient: the larger incremental inductance at zero current >= 1.2 x the smaller
EXPECT = {"fluxdrive": ("+d", "q"), "syr": ("-q", "d")}  # PM axis, axis of the larger inductance


@dataclass
class Found:
    convention: str | None  # "fluxdrive", "syr", or None (not detectable, or neither)
    pm_axis: str | None  # "+d", "+q", "-d", "-q", "off-axis" or None (no PM flux)
    pm_flux: float
    l_dd: float
    l_qq: float
    evidence: str  # what the data show, in words ("" when nothing)


def _zero_current(i_d, i_q, psi_d, psi_q):
    """lambda(0) and the incremental l_dd, l_qq there (over one step each
    side; one-sided at a grid edge), in the file's frame."""
    m = FluxMap(np.asarray(i_d, float), np.asarray(i_q, float), psi_d, psi_q, 1)
    d0 = float(np.clip(0.0, m.i_d[0], m.i_d[-1]))
    q0 = float(np.clip(0.0, m.i_q[0], m.i_q[-1]))
    f = m.flux(d0, q0)
    da = (min(d0 + m.did, m.i_d[-1]), max(d0 - m.did, m.i_d[0]))
    qa = (min(q0 + m.diq, m.i_q[-1]), max(q0 - m.diq, m.i_q[0]))
    l_dd = (m.flux(da[0], q0)[0] - m.flux(da[1], q0)[0]) / (da[0] - da[1])
    l_qq = (m.flux(d0, qa[0])[1] - m.flux(d0, qa[1])[1]) / (qa[0] - qa[1])
    return float(f[0]), float(f[1]), float(l_dd), float(l_qq)


def detect_convention(i_d, i_q, psi_d, psi_q) -> Found:
    """The PM axis (the flux at zero current) and the saliency (the larger
    incremental self-inductance at zero current) in the file's frame, and
    the convention they give: PM on +d -> fluxdrive, on -q -> syr (on +q
    or -d: neither); without a PM flux, the larger inductance on q ->
    fluxdrive, on d -> syr."""
    psi_d, psi_q = np.asarray(psi_d, float), np.asarray(psi_q, float)
    if not (np.all(np.isfinite(psi_d)) and np.all(np.isfinite(psi_q))):
        return Found(None, None, 0.0, 0.0, 0.0, "")
    fd, fq, l_dd, l_qq = _zero_current(i_d, i_q, psi_d, psi_q)
    pm = float(np.hypot(fd, fq))
    scale = float(np.hypot(psi_d, psi_q).max())
    sal = ""
    big = None
    if l_dd > 0 and l_qq > 0 and max(l_dd, l_qq) >= SALIENCY * min(l_dd, l_qq):
        big = "q" if l_qq > l_dd else "d"
        sal = (f"the larger incremental inductance at zero current on {big} (l_dd "
               f"{l_dd * 1e3:.4g} mH, l_qq {l_qq * 1e3:.4g} mH)")
    if pm > PM_FRAC * scale:
        ang = float(np.degrees(np.arctan2(fq, fd)))
        axes = {"+d": 0.0, "+q": 90.0, "-d": 180.0, "-q": -90.0}
        name, off = min(((k, abs((ang - a + 180.0) % 360.0 - 180.0)) for k, a in axes.items()),
                        key=lambda x: x[1])
        axis = name if off <= PM_AXIS_DEG else "off-axis"
        where = (f"on {axis}" if axis != "off-axis" else
                 f"at {ang:.1f} deg from +d, on no axis (within {PM_AXIS_DEG:g} deg)")
        ev = f"the PM flux at zero current {where} ({pm:.4g} Vs)"
        conv = {"+d": "fluxdrive", "-q": "syr"}.get(axis)
        return Found(conv, axis, pm, l_dd, l_qq, ev + (f" and {sal}" if sal else ""))
    conv = {"q": "fluxdrive", "d": "syr"}.get(big) if big else None
    ev = (f"no PM flux at zero current ({pm:.3g} Vs) and {sal}" if sal else "")
    return Found(conv, None, pm, l_dd, l_qq, ev)


def check_convention(file: str, stated: str | None, found: Found) -> str:
    """The convention to use: the stated one if the data agree (or show
    nothing), else refused naming what the data show; the detected one if
    none is stated, else fluxdrive."""
    if found.pm_axis in ("+q", "-d", "off-axis"):
        raise FluxMapError(file, "convention: the data fit neither",
                           found.evidence + "; fluxdrive's convention has the PM on +d, the SyR "
                           "convention on -q" +
                           ("; d and q exchanged in the file?" if found.pm_axis == "+q" else
                            "; the d axis reversed in the file?" if found.pm_axis == "-d" else
                            "; the map's rotor angle is not aligned with the PM"))
    if stated is not None and found.convention is not None and found.convention != stated:
        pm, big = EXPECT[stated]
        raise FluxMapError(file, f"convention {stated} contradicts the data",
                           f"{found.evidence}: the {found.convention} convention (stated "
                           f"{stated}: PM on {pm}, the larger inductance on {big}); pass "
                           f"--convention {found.convention} (or fix the file's convention)")
    return stated or found.convention or "fluxdrive"


# --- plausibility of the units (docs/flux-maps.md, "Checks of the data") ---

PSI_MAX = 10.0  # Vs: no flux linkage of a machine a drive like this one runs beyond it
L_MAX = 10.0  # H: incremental inductance at zero current
L_MIN = 1e-6  # H
I_RATIO = 100.0  # the map's current range beyond 100 x i_max: not the machine's amperes
EMF_RATIO = 10.0  # back-EMF at the stated speed beyond 10 x v_dc / sqrt(3)


def check_units(file: str, m: FluxMap, i_max: float | None = None, v_dc: float | None = None,
                speed_rpm: float | None = None) -> None:
    """Refuses magnitudes no machine has, naming the likely unit error."""
    flux = np.hypot(m.psi_d, m.psi_q)
    k = np.unravel_index(int(np.argmax(flux)), flux.shape)
    big = float(flux[k])
    pm = abs(m.pm_flux())
    if big > PSI_MAX:
        raise FluxMapError(file, "flux linkages implausible (unit?)",
                           f"the largest flux linkage {big:.4g} Vs (at i_d = {m.i_d[k[1]]:g} A, "
                           f"i_q = {m.i_q[k[0]]:g} A; PM flux {pm:.4g} Vs) is beyond any machine "
                           f"(<= {PSI_MAX:g} Vs); psi looks like mVs: divide by 1000 or pass "
                           "--flux-unit mVs")
    l0 = m.inductance(0.0, 0.0)
    for name, l in (("l_dd", l0[0]), ("l_qq", l0[3])):
        if l > L_MAX:
            raise FluxMapError(file, "inductance implausible (unit?)",
                               f"{name} at zero current {l:.4g} H is beyond any machine (<= "
                               f"{L_MAX:g} H): flux in mVs (--flux-unit mVs) or currents in "
                               "mA read as A?")
        if l < L_MIN:
            raise FluxMapError(file, "inductance implausible (unit?)",
                               f"{name} at zero current {l:.4g} H is below any machine (>= "
                               f"{L_MIN:g} H): currents in mA? divide them by 1000 or pass "
                               "--current-unit mA")
    i_range = float(max(abs(m.i_d[0]), abs(m.i_d[-1]), abs(m.i_q[0]), abs(m.i_q[-1])))
    if i_max is not None and i_max > 0 and i_range > I_RATIO * i_max:
        raise FluxMapError(file, "currents implausible (unit?)",
                           f"the map's currents reach {i_range:g} A, {i_range / i_max:.0f} x the "
                           f"machine's i_max {i_max:g} A (> {I_RATIO:g} x): currents in mA? "
                           "divide them by 1000 or pass --current-unit mA")
    if v_dc and speed_rpm and pm > 0:
        emf = pm * abs(speed_rpm) * 2 * np.pi / 60 * m.pole_pairs
        v = v_dc / np.sqrt(3.0)
        if emf > EMF_RATIO * v:
            raise FluxMapError(file, "flux linkages implausible (unit?)",
                               f"the PM flux {pm:.4g} Vs gives {emf:.4g} V phase peak at "
                               f"{speed_rpm:g} rpm, {emf / v:.0f} x v_dc / sqrt(3) = {v:.4g} V "
                               f"(> {EMF_RATIO:g} x): psi looks like mVs: divide by 1000 or pass "
                               "--flux-unit mVs")
        if emf > v:
            m.notes.append(f"warning: the PM flux gives {emf:.4g} V phase peak at {speed_rpm:g} "
                           f"rpm, above v_dc / sqrt(3) = {v:.4g} V (uncontrolled generation if "
                           "the drive trips there)")


# --- the tables' range (docs/flux-maps.md, "Half-range maps") ---

EDGE_SLOPE = 0.01  # 1/rad: torque still rising past the i_d edge by more than this: refused


def check_tables(file: str, m: FluxMap) -> None:
    """The MTPA table needs i_d from 0 down (a PM or reluctance machine in
    fluxdrive's frame has its MTPA at i_d <= 0) and i_q from 0 up; a map
    whose MTPA lies beyond its largest i_d (at i_d > 0: reverse saliency)
    is refused."""
    from .luts import tables

    if not (m.i_d[0] < 0.0 <= m.i_d[-1] + 1e-9 * m.did):
        raise FluxMapError(file, "i_d range cannot hold the MTPA",
                           f"i_d from {m.i_d[0]:g} to {m.i_d[-1]:g} A: the MTPA table needs i_d "
                           "from 0 down to the current limit (fluxdrive frame: the PM on +d, "
                           "MTPA at i_d <= 0); give the map for i_d <= 0 at least")
    t = tables(m)
    if t.edge is not None:
        amp, slope, edge = t.edge
        raise FluxMapError(file, "MTPA beyond the map's i_d range",
                           f"at {amp:.4g} A the torque still rises by {slope:.3g} per rad towards "
                           f"i_d > {edge:g} A, the map's largest i_d (> {EDGE_SLOPE:g}): the MTPA "
                           "lies outside the map (reverse saliency?); give the map for larger "
                           "i_d")
