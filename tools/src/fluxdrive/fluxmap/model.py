"""A flux map in fluxdrive's frame (d on the PM flux; d on the minimum
inductance of a reluctance machine): lambda_d, lambda_q on a regular grid
of i_d, i_q, arrays of shape (len(i_q), len(i_d)) (row = i_q index), with
bilinear lookups as the core does them (firmware/core/model/flux_map.c)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class FluxMap:
    i_d: np.ndarray  # 1-D, increasing, regular [A]
    i_q: np.ndarray
    psi_d: np.ndarray  # (nq, nd) [Vs]
    psi_q: np.ndarray
    pole_pairs: int
    name: str = "map"
    notes: list[str] = field(default_factory=list)  # what was done on load (mirror, ...)
    cache: dict = field(default_factory=dict, repr=False, compare=False)  # tables (luts)

    @property
    def nd(self) -> int:
        return len(self.i_d)

    @property
    def nq(self) -> int:
        return len(self.i_q)

    @property
    def did(self) -> float:
        return float(self.i_d[1] - self.i_d[0])

    @property
    def diq(self) -> float:
        return float(self.i_q[1] - self.i_q[0])

    def _cell(self, i_d, i_q):
        x = (np.asarray(i_d, float) - self.i_d[0]) / self.did
        y = (np.asarray(i_q, float) - self.i_q[0]) / self.diq
        j = np.clip(np.floor(np.clip(x, 0, self.nd - 2)), 0, self.nd - 2).astype(int)
        k = np.clip(np.floor(np.clip(y, 0, self.nq - 2)), 0, self.nq - 2).astype(int)
        return j, k, x - j, y - k

    def flux(self, i_d, i_q):
        """Bilinear lambda_d, lambda_q (linear extrapolation outside)."""
        j, k, u, v = self._cell(i_d, i_q)
        out = []
        for a in (self.psi_d, self.psi_q):
            f00, f10, f01, f11 = a[k, j], a[k, j + 1], a[k + 1, j], a[k + 1, j + 1]
            lo = f00 + u * (f10 - f00)
            hi = f01 + u * (f11 - f01)
            out.append(lo + v * (hi - lo))
        return out[0], out[1]

    def flux_smooth(self, i_d, i_q):
        """Bicubic (Catmull-Rom, C1) lambda_d, lambda_q inside the grid, for
        the tables: the plant's interpolant is C1 too, and an optimum (MTPA,
        MTPV) on a bilinear surface sits on cell edges."""
        x = np.clip((np.asarray(i_d, float) - self.i_d[0]) / self.did, 0, self.nd - 1)
        y = np.clip((np.asarray(i_q, float) - self.i_q[0]) / self.diq, 0, self.nq - 1)
        j = np.clip(np.floor(x).astype(int), 0, self.nd - 2)
        k = np.clip(np.floor(y).astype(int), 0, self.nq - 2)
        u, v = x - j, y - k

        def w(t):
            return (0.5 * (-t + 2 * t * t - t ** 3), 0.5 * (2 - 5 * t * t + 3 * t ** 3),
                    0.5 * (t + 4 * t * t - 3 * t ** 3), 0.5 * (-t * t + t ** 3))

        wu, wv = w(u), w(v)
        out = []
        for a in (self.psi_d, self.psi_q):
            acc = 0.0
            for dk in range(4):
                kk = np.clip(k + dk - 1, 0, self.nq - 1)
                row = 0.0
                for dj in range(4):
                    jj = np.clip(j + dj - 1, 0, self.nd - 1)
                    row = row + wu[dj] * a[kk, jj]
                acc = acc + wv[dk] * row
            out.append(acc)
        return out[0], out[1]

    def torque_smooth(self, i_d, i_q):
        pd, pq = self.flux_smooth(i_d, i_q)
        return 1.5 * self.pole_pairs * (pd * np.asarray(i_q) - pq * np.asarray(i_d))

    def torque(self, i_d, i_q):
        """T = 3/2 p (lambda_d i_q - lambda_q i_d), Varatharajan (4)."""
        pd, pq = self.flux(i_d, i_q)
        return 1.5 * self.pole_pairs * (pd * np.asarray(i_q) - pq * np.asarray(i_d))

    def inductance(self, i_d, i_q):
        """Incremental inductances l_dd, l_dq, l_qd, l_qq: (25) centred over one step."""
        hd, hq = 0.5 * self.did, 0.5 * self.diq
        dp, dm = self.flux(np.asarray(i_d) + hd, i_q), self.flux(np.asarray(i_d) - hd, i_q)
        qp, qm = self.flux(i_d, np.asarray(i_q) + hq), self.flux(i_d, np.asarray(i_q) - hq)
        return ((dp[0] - dm[0]) / self.did, (qp[0] - qm[0]) / self.diq,
                (dp[1] - dm[1]) / self.did, (qp[1] - qm[1]) / self.diq)

    def pm_flux(self) -> float:
        return float(self.flux(0.0, 0.0)[0])


def syr_to_fluxdrive(i_d, i_q, psi_d, psi_q):
    """The SyR convention (d on the maximum inductance, PM on -q) into
    fluxdrive's: x_d(fd) = -x_q(SyR), x_q(fd) = x_d(SyR) (a -90 deg turn).
    Grids in: 1-D i_d, i_q (SyR), arrays (len(i_q), len(i_d)); out: the same
    in fluxdrive's frame, axes increasing."""
    i_d, i_q = np.asarray(i_d, float), np.asarray(i_q, float)
    new_id = -i_q[::-1] + 0.0  # no -0.0
    new_iq = i_d.copy()
    # mut: syr_convention_psi_d_sign
    new_psi_d = -np.asarray(psi_q, float).T[:, ::-1]
    new_psi_q = np.asarray(psi_d, float).T[:, ::-1].copy()
    return new_id, new_iq, new_psi_d, new_psi_q


def fluxdrive_to_syr(i_d, i_q, psi_d, psi_q):
    """The inverse turn (+90 deg): x_d(SyR) = x_q(fd), x_q(SyR) = -x_d(fd)."""
    i_d, i_q = np.asarray(i_d, float), np.asarray(i_q, float)
    new_id = i_q.copy()
    new_iq = -i_d[::-1] + 0.0
    new_psi_d = np.asarray(psi_q, float)[:, ::-1].T.copy()
    new_psi_q = -np.asarray(psi_d, float)[:, ::-1].T
    return new_id, new_iq, new_psi_d, new_psi_q
