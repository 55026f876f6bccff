"""A map's summary: grid, PM flux, inductances, the MTPA table's ends."""

from __future__ import annotations

import numpy as np

from .luts import mtpv_label, tables
from .model import FluxMap


def rated_point(m: FluxMap, amp: float):
    """MTPA current, torque and flux at current amplitude amp."""
    t = tables(m)
    th = np.interp(amp, t.amp, np.arctan2(t.amp_iq, t.amp_id))
    i_d, i_q = amp * np.cos(th), amp * np.sin(th)
    pd, pq = m.flux(i_d, i_q)
    return float(i_d), float(i_q), float(m.torque(i_d, i_q)), float(np.hypot(pd, pq))


def describe(m: FluxMap) -> str:
    t = tables(m)
    l0 = m.inductance(0.0, 0.0)
    out = [f"map {m.name}: {m.nd} x {m.nq} points, i_d {m.i_d[0]:g} .. {m.i_d[-1]:g} A, "
           f"i_q {m.i_q[0]:g} .. {m.i_q[-1]:g} A, {m.pole_pairs} pole pairs (fluxdrive frame)",
           f"PM flux (lambda_d at zero current): {m.pm_flux():.4f} Vs",
           f"incremental inductances at zero current: l_dd {l0[0] * 1e3:.2f} mH, "
           f"l_qq {l0[3] * 1e3:.2f} mH, l_dq {l0[1] * 1e3:.3f} mH",
           f"MTPA table: 0 .. {t.mtpa_t_max:.3f} N m (current amplitude up to "
           f"{t.amp[-1]:.2f} A); MTPV table: flux 0 .. {t.mtpv_flux_max:.3f} Vs",
           f"MTPV table: {mtpv_label(t)}"]
    out += [f"note: {n}" for n in m.notes]
    return "\n".join(out)
