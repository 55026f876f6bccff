"""The analytic machines of the presets (docs/flux-maps.md): Hinkkanen 2017
models in the SyR convention, gridded in fluxdrive's frame.

syr_1k1, a 1.1 kW SyR machine consistent with Varatharajan et al. 2022,
Table I (p = 2, R_s = 6.8 Ohm, 2.3 A rms, 7.1 N m, 1500 rpm, J = 0.04
kg m^2). Fit: the 5.5 kW SyRM parameters of the model's authors' examples
(a_d0 17.4, a_dd 373, S 5, a_q0 52.1, a_qq 658, T 1, a_dq 1120, U 1, V 0)
scaled in current by k and in flux by c,
i(psi) -> k i(psi / c), with the q-axis (minimum inductance) terms a
further r = 3 (more saliency): c = 2 sets the rated flux near 0.93 Vs (the
rated line voltage 340 V rms at 1500 rpm), k by bisection so that MTPA at
the rated 2.3 sqrt(2) A gives 7.1 N m (SYR_K). The figures the fit gives
are printed by `fluxdrive map check preset:syr_1k1` and in the docs page.

ipm_sat: an interior-PM machine (p = 4, 0.08 Vs PM flux, L_d 3.3 mH,
L_q 8 mH unsaturated, characteristic current about 24 A inside the
40 A grid, so that MTPV is on the map) with self- and cross-saturation. pmasyr: a PM-assisted SyR machine (p = 2, 0.12 Vs), the
source of the map-file preset maps/pmasyr_file.{npz,csv} (stored in the
SyR convention, complex arrays).
"""

from __future__ import annotations

import numpy as np

from .analytic import Hinkkanen
from .errors import FluxMapError
from .model import FluxMap, syr_to_fluxdrive

SYR_C, SYR_R = 2.0, 3.0
SYR_K = 0.137396  # bisection: 7.1 N m at 3.2527 A on MTPA (the tests check it)
_S, _T, _U, _V = 5, 1, 1, 0


def _scaled(k: float, c: float, r: float, psi_pm: float = 0.0) -> Hinkkanen:
    return Hinkkanen(a_d0=k * 17.4 / c, a_dd=k * 373.0 / c ** (_S + 1), S=_S,
                     a_q0=r * k * 52.1 / c, a_qq=r * k * 658.0 / c ** (_T + 1), T=_T,
                     a_dq=k * 1120.0 / c ** (_U + _V + 3), U=_U, V=_V, psi_pm=psi_pm)


# name: (model, pole pairs, grid half-width in A, points per axis)
MODELS = {
    "syr_1k1": (_scaled(SYR_K, SYR_C, SYR_R), 2, 8.0, 33),
    "ipm_sat": (Hinkkanen(a_d0=125.0, a_dd=4.0e5, S=4, a_q0=300.0, a_qq=1.0e3, T=1,
                          a_dq=2.0e5, U=1, V=0, psi_pm=0.08), 4, 40.0, 41),
    "pmasyr": (_scaled(0.3, 1.5, 3.0, psi_pm=0.12), 2, 10.0, 41),
}


def model(name: str) -> tuple[Hinkkanen, int]:
    if name not in MODELS:
        raise FluxMapError(f"preset:{name}", "unknown preset", ", ".join(MODELS))
    m, p, _, _ = MODELS[name]
    return m, p


def grid_syr(name: str):
    """The preset's map in the SyR convention on its grid: i_d, i_q (1-D),
    psi_d, psi_q (len(i_q), len(i_d))."""
    m, _, half, n = MODELS[name]
    a = np.linspace(-half, half, n)
    D, Q = np.meshgrid(a, a)
    pd, pq = m.flux(D, Q)
    return a, a.copy(), pd, pq


def preset_map(name: str) -> FluxMap:
    model(name)
    _, p, _, _ = MODELS[name]
    i_d, i_q, pd, pq = syr_to_fluxdrive(*grid_syr(name))
    return FluxMap(i_d, i_q, pd, pq, p, name, ["analytic preset (Hinkkanen 2017), SyR convention "
                                               "turned into fluxdrive's"])
