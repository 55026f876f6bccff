"""The load-dependent phase shifts of the star point's DFC signal (Fabbri
2022, 3.3.3, (3.97)-(3.100)), issue 23 point 6: the plant's model of them,
and their identification from a run, both shifts apart.

The plant (sil/plant/plant.h) turns the self (L2) and mutual (M2) 2theta
terms of the (3.3) matrix apart with the load: machine.star_phi_self,
machine.star_phi_mutual [rad/A] (machine.star_phi_iq sets both). (3.7) with
L2, M2 as phasors gives (3.97) exactly (plant_aniso_load, checked against
the divider in tests/plant/test_star_point.c):

    phi_a = arg(L2 e^{j s} - M2 e^{j m}) - arg(L2 - M2)
    phi_b = phi_a + arg(L2/2 e^{j s} + M2 e^{j m}) - arg(L2/2 + M2)
    p     = |L2/2 e^{j s} + M2 e^{j m}| / (L0 - M0),   s, m = phi_self i_q, phi_mut i_q

Identification: (3.97) as one complex signal is

    z = -Gamma_alpha + j Gamma_beta = a e^{j(2 theta + phi_a)} - b e^{-j(4 theta + phi_b)},

linear in the two unknown phasors A = a e^{j phi_a}, B = -b e^{-j phi_b}
given the angle: least squares on the logged signals (dfc_ga..gc) at the
encoder's angle, per current step, each phase against the unloaded step's
(what the sampling adds to the phase is the same at every load and
cancels), then the slope over i_q. The thesis fitted its shifts offline
(MATLAB's identification toolbox, Fig. 5.5).
"""

from __future__ import annotations

import numpy as np

# The Table 5.1 motor's star point (sil/runner/presets.c fabbri2022_t51)
T51 = {"ld": 394e-6, "lq": 475e-6, "m2": -48.54e-6}


def load_shifts(phi_self: float, phi_mut: float, i_q: float, ld: float = T51["ld"],
                lq: float = T51["lq"], m2: float = T51["m2"]) -> tuple[float, float, float]:
    """(phi_a, phi_b [rad], p) of (3.97) at the load i_q: plant_aniso_load."""
    l2 = (ld - lq) - 2.0 * m2
    s, m = np.exp(1j * phi_self * i_q), np.exp(1j * phi_mut * i_q)
    za, zb = l2 * s - m2 * m, 0.5 * l2 * s + m2 * m
    pa = float(np.angle(za / (l2 - m2)))
    b0 = 0.5 * l2 + m2
    pb = pa + (float(np.angle(zb / b0)) if b0 != 0.0 else 0.0)
    return pa, pb, float(np.sign(b0) * abs(zb) / (0.5 * (ld + lq)))


def self_mutual_for(phi_a: float, phi_b: float, i_ref: float, **machine) -> tuple[float, float]:
    """The plant's (phi_self, phi_mut) [rad/A] whose (3.97) shifts at i_ref
    are phi_a i_ref, phi_b i_ref (Newton on load_shifts; the shifts are
    near linear in i_q below it)."""
    x = np.array([phi_a, phi_b - phi_a])  # a start: equal shifts give (phi, 2 phi)
    want = np.array([phi_a, phi_b]) * i_ref
    for _ in range(50):
        f = np.array(load_shifts(x[0], x[1], i_ref, **machine)[:2]) - want
        if np.max(np.abs(f)) < 1e-12:
            break
        jac = np.empty((2, 2))
        for k in range(2):
            d = np.zeros(2)
            d[k] = 1e-7
            jac[:, k] = (np.array(load_shifts(*(x + d), i_ref, **machine)[:2]) - want - f) / 1e-7
        x = x - np.linalg.solve(jac, f)
    else:
        raise ValueError(f"no plant shifts for phi_a {phi_a}, phi_b {phi_b}")
    return float(x[0]), float(x[1])


def true_slopes(phi_self: float, phi_mut: float, i_ref: float, **machine) -> tuple[float, float]:
    """The plant's (3.97) shifts as the drive's model has them, phi i_q:
    the secant at i_ref [rad/A]."""
    pa, pb, _ = load_shifts(phi_self, phi_mut, i_ref, **machine)
    return pa / i_ref, pb / i_ref


def signal_phasors(lg, m, pole_pairs: int) -> tuple[complex, complex]:
    """A = a e^{j phi_a}, B = -b e^{-j phi_b} of (3.97): least squares of
    the logged signals (plain Clarke vector of dfc_ga..gc) on the encoder's
    angle at their instant (t + dfc_t), with an offset, over the rows m."""
    g = np.stack([lg["dfc_ga"][m], lg["dfc_gb"][m], lg["dfc_gc"][m]])
    al = (2.0 * g[0] - g[1] - g[2]) / 3.0
    be = (g[1] - g[2]) / np.sqrt(3.0)
    th = lg["theta_e_enc"][m] + pole_pairs * lg["speed"][m] * lg["dfc_t"][m]
    z = -al + 1j * be
    x = np.stack([np.exp(2j * th), np.exp(-4j * th), np.ones_like(th)], axis=1)
    c = np.linalg.lstsq(x, z, rcond=None)[0]
    return complex(c[0]), complex(c[1])


def fit_shifts(iq: np.ndarray, phasors: list) -> tuple[float, float, np.ndarray, np.ndarray]:
    """phi_a, phi_b [rad/A]: the slopes over i_q of each term's phase from
    the first (unloaded) step's; and the per-step phases [rad]."""
    a0, b0 = phasors[0]
    pa = np.array([np.angle(a / a0) for a, _ in phasors])
    pb = np.array([-np.angle(b / b0) for _, b in phasors])
    return float(np.polyfit(iq, pa, 1)[0]), float(np.polyfit(iq, pb, 1)[0]), pa, pb
