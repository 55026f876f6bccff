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
