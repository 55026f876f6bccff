"""Analytic saturated machine: the algebraic current-from-flux model of
Hinkkanen et al., "Sensorless self-commissioning of synchronous reluctance
motors at standstill without rotor locking", IEEE Trans. Ind. Appl. 53(3),
2017, with an optional PM term.

SyR convention (d on the maximum inductance, PM on -q), currents from flux
linkages:

    i_d = (a_d0 + a_dd |psi_d|^S + a_dq / (V + 2) |psi_d|^U |psi_q'|^(V + 2)) psi_d
    i_q = (a_q0 + a_qq |psi_q'|^T + a_dq / (U + 2) |psi_d|^(U + 2) |psi_q'|^V) psi_q'

with psi_q' = psi_q + psi_pm. Both are the gradient of one magnetic energy

    W(psi) = a_d0 psi_d^2 / 2 + a_dd |psi_d|^(S+2) / (S+2) + a_q0 psi_q'^2 / 2
             + a_qq |psi_q'|^(T+2) / (T+2)
             + a_dq |psi_d|^(U+2) |psi_q'|^(V+2) / ((U+2)(V+2)),

so the cross-saturation is reciprocal (d i_d / d psi_q = d i_q / d psi_d,
hence d psi_d / d i_q = d psi_q / d i_d). a_d0 = 1/L_d0, a_q0 = 1/L_q0 are
the inverse unsaturated inductances [1/H]; a_dd, a_qq the self-saturation
and a_dq the cross-saturation coefficients [A/Vs^(n+1)]; S, T, U, V the
exponents (S, T >= 0; U, V >= 0). The flux map lambda(i) is the inverse,
by Newton (vectorised), to ~1e-13 relative.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Hinkkanen:
    a_d0: float
    a_dd: float
    S: float
    a_q0: float
    a_qq: float
    T: float
    a_dq: float
    U: float
    V: float
    psi_pm: float = 0.0  # PM flux, on -q (SyR convention) [Vs]

    def current(self, psi_d, psi_q):
        """i_d, i_q (SyR convention) from psi_d, psi_q."""
        d = np.abs(psi_d)
        qp = psi_q + self.psi_pm
        q = np.abs(qp)
        i_d = (self.a_d0 + self.a_dd * d ** self.S
               + self.a_dq / (self.V + 2) * d ** self.U * q ** (self.V + 2)) * psi_d
        i_q = (self.a_q0 + self.a_qq * q ** self.T
               + self.a_dq / (self.U + 2) * d ** (self.U + 2) * q ** self.V) * qp
        return i_d, i_q

    def jacobian(self, psi_d, psi_q):
        """d i / d psi (SyR convention): (g_dd, g_dq, g_qd, g_qq), g_dq = g_qd."""
        d = np.abs(psi_d)
        qp = psi_q + self.psi_pm
        q = np.abs(qp)
        S, T, U, V = self.S, self.T, self.U, self.V
        g_dd = (self.a_d0 + (S + 1) * self.a_dd * d ** S
                + (U + 1) * self.a_dq / (V + 2) * d ** U * q ** (V + 2))
        g_qq = (self.a_q0 + (T + 1) * self.a_qq * q ** T
                + (V + 1) * self.a_dq / (U + 2) * d ** (U + 2) * q ** V)
        g_dq = self.a_dq * np.sign(psi_d) * np.sign(qp) * d ** (U + 1) * q ** (V + 1)
        return g_dd, g_dq, g_dq, g_qq

    def flux(self, i_d, i_q, iters: int = 60):
        """psi_d, psi_q (SyR convention) at currents i_d, i_q (arrays) by Newton."""
        i_d = np.asarray(i_d, dtype=float)
        i_q = np.asarray(i_q, dtype=float)
        pd = i_d / self.a_d0
        pq = i_q / self.a_q0 - self.psi_pm
        for _ in range(iters):
            cd, cq = self.current(pd, pq)
            rd, rq = i_d - cd, i_q - cq
            gdd, gdq, _, gqq = self.jacobian(pd, pq)
            det = gdd * gqq - gdq * gdq
            sd = (gqq * rd - gdq * rq) / det
            sq = (gdd * rq - gdq * rd) / det
            # damped: never more than halfway to zero flux in one step
            lim = 0.5 * (np.abs(pd) + np.abs(pq + self.psi_pm)) + 0.05
            scale = np.minimum(1.0, lim / np.maximum(np.hypot(sd, sq), 1e-300))
            pd = pd + scale * sd
            pq = pq + scale * sq
            if np.all(np.abs(rd) + np.abs(rq) < 1e-12 * (1.0 + np.abs(i_d) + np.abs(i_q))):
                break
        return pd, pq
