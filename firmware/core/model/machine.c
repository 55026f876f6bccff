/*
 * machine.c - the machine_t interface: the linear machine here, the
 * flux-map machine by dispatch to flux_map.c.
 */
#include "model/machine.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"

/* Halley steps of the MTPA inversion of the linear machine
 * (machine_mtpa_current): from the starting point there, 2 steps bring w
 * within 2.4e-6 relative of the root over the whole range (c / lambda_m^4
 * from 1e-12 to 1e12, lambda_m from 1e-3 to 30 Vs, in float; Newton from
 * the bounds min(c / lambda_m^3, c^(1/4)) needed 5 steps, a division each,
 * for 2e-7: issue 24 point 8, the speed loop's ISR). The torque is then
 * within 3.5e-6 relative of t; tests/core/test_machine.c checks it
 * (1e-4) and the current amplitude against a brute-force MTPA. */
#define MACHINE_MTPA_HALLEY 2
/* the starting point's weight of c^(1/4) (machine_mtpa_current): the
 * smallest worst error of the two steps over that range (0.6: 1e-5, 0.75:
 * 1.5e-5) */
#define MACHINE_MTPA_START_K 0.67f

int machine_init_linear(machine_t *m, float pole_pairs, float rs, float ld, float lq,
                        float lambda_m) {
  const float z = fd_zero_if_finite(pole_pairs) + fd_zero_if_finite(rs) + fd_zero_if_finite(ld) +
                  fd_zero_if_finite(lq) + fd_zero_if_finite(lambda_m);
  if (!(fd_isfinite(z) && pole_pairs >= 1.0f && rs > 0.0f && ld > 0.0f && lq > 0.0f &&
        lambda_m >= 0.0f)) {
    return -1;
  }
  *m = (machine_t){MACHINE_LINEAR, pole_pairs, rs, ld, lq, lambda_m, NULL};
  return 0;
}

FD_COLD int machine_init_map(machine_t *m, float rs, const flux_map_t *map) {
  if (map == NULL || !(fd_isfinite(rs) && rs > 0.0f)) {
    return -1;
  }
  const flux_map_ldq_t l = flux_map_inductance(map, (dq_t){0.0f, 0.0f});
  const dq_t l0 = flux_map_flux(map, (dq_t){0.0f, 0.0f});
  *m = (machine_t){MACHINE_FLUX_MAP, map->pole_pairs, rs, l.dd, l.qq, fd_maxf(l0.d, 0.0f), map};
  return 0;
}

dq_t machine_flux(const machine_t *m, dq_t i) {
  if (m->kind == MACHINE_FLUX_MAP) {
    return flux_map_flux(m->map, i);
  }
  return (dq_t){m->ld * i.d + m->lambda_m, m->lq * i.q};
}

dq_t machine_current(const machine_t *m, dq_t lambda) {
  if (m->kind == MACHINE_FLUX_MAP) {
    return flux_map_current(m->map, lambda);
  }
  return (dq_t){(lambda.d - m->lambda_m) / m->ld, lambda.q / m->lq};
}

machine_ldq_t machine_inductance(const machine_t *m, dq_t i) {
  if (m->kind == MACHINE_FLUX_MAP) {
    return flux_map_inductance(m->map, i);
  }
  return (machine_ldq_t){m->ld, 0.0f, 0.0f, m->lq}; /* linear: independent of i */
}

dq_t machine_flux_inductance(const machine_t *m, dq_t i, machine_ldq_t *l) {
  if (m->kind == MACHINE_FLUX_MAP) {
    return flux_map_flux_inductance(m->map, i, l); /* in place: one type */
  }
  *l = (machine_ldq_t){m->ld, 0.0f, 0.0f, m->lq};
  return (dq_t){m->ld * i.d + m->lambda_m, m->lq * i.q};
}

float machine_torque(const machine_t *m, dq_t i) {
  const dq_t l = machine_flux(m, i);
  return 1.5f * m->pole_pairs * (l.d * i.q - l.q * i.d);
}

float machine_pm_flux(const machine_t *m) {
  return m->lambda_m;
}

int machine_is_isotropic(const machine_t *m, float rel_tol) {
  return m->kind == MACHINE_LINEAR && fabsf(m->lq - m->ld) <= rel_tol * m->ld;
}

/* MTPA of the linear machine at current amplitude I (d lambda_d/d i_d = Ld,
 * dL = Lq - Ld): i_d = (lambda_m - s) / (4 dL), s = sqrt(lambda_m^2 +
 * 8 dL^2 I^2), written without the cancellation at small dL:
 * i_d = -2 dL I^2 / (lambda_m + s); i_q = sqrt(I^2 - i_d^2) >= 0. */
static dq_t mtpa_at(const machine_t *m, float i_amp) {
  const float dl = m->lq - m->ld;
  const float s = sqrtf(m->lambda_m * m->lambda_m + 8.0f * dl * dl * i_amp * i_amp);
  const float den = m->lambda_m + s;
  const float id = den > 0.0f ? -2.0f * dl * i_amp * i_amp / den : 0.0f;
  return (dq_t){id, sqrtf(fd_maxf(i_amp * i_amp - id * id, 0.0f))};
}

float machine_mtpa_torque(const machine_t *m, float i_amp) {
  if (m->kind == MACHINE_FLUX_MAP) {
    return flux_map_mtpa_torque(m->map, fd_maxf(i_amp, 0.0f));
  }
  return machine_torque(m, mtpa_at(m, fd_maxf(i_amp, 0.0f)));
}

/* MTPA current of torque t. On the linear machine's MTPA locus
 * (mtpa_at: i_q^2 = i_d^2 - lambda_m i_d / dL, dL = Lq - Ld), with
 * w = -dL i_d >= 0 (the reluctance share of the d flux),
 *     i_q = sqrt(w (w + lambda_m)) / |dL|,  T = k i_q (lambda_m + w)
 * so that T^2 = k^2 w (w + lambda_m)^3 / dL^2: w solves the quartic
 *     F(w) = w (w + lambda_m)^3 - c = 0,  c = (|t| |dL| / k)^2,
 * F convex and increasing for w >= 0 (all its coefficients >= 0), so
 * Newton from above would approach monotonically, but a step at a
 * time: Halley's iteration (cubic convergence; e.g. Press et al.,
 * Numerical Recipes, 3rd ed., section 9.4)
 *     w <- w - 2 F F' / (2 F'^2 - F F''),
 *     F' = v^2 (4 w + lambda_m),  F'' = 6 v (v + w),  v = w + lambda_m,
 * one division a step, no square root. Start: c^(1/4) (the root without a
 * magnet, an upper bound: F(w) >= w^4 - c) or, smaller, the root of the
 * magnet-dominated end w (lambda_m + K c^(1/4))^3 = c, K =
 * MACHINE_MTPA_START_K: exact to first order at small c, c^(1/4) at large
 * c, and between them (c ~ lambda_m^4, where the two bounds are both 3
 * times the root) within a factor 2.1. Iterating on w, not on
 * w + lambda_m, keeps a nearly isotropic machine's small w exact. */
dq_t machine_mtpa_current(const machine_t *m, float t) {
  const float k = 1.5f * m->pole_pairs;
  const float dl = m->lq - m->ld;
  const float ta = fabsf(t);
  if (m->kind == MACHINE_FLUX_MAP) {
    return fd_isfinite(t) ? flux_map_mtpa_current(m->map, t) : (dq_t){0.0f, 0.0f};
  }
  if (!fd_isfinite(t) || !(m->lambda_m > 0.0f || fabsf(dl) > 0.0f)) {
    return (dq_t){0.0f, 0.0f};
  }
  const float lm = m->lambda_m;
  if (!(fabsf(dl) > 0.0f)) { /* isotropic: the PM torque alone */
    return (dq_t){0.0f, t / (k * lm)};
  }
  const float adl = fabsf(dl);
  const float x = ta * adl / k;
  const float c = x * x;
  float w = sqrtf(x); /* c^(1/4) */
  if (lm > 0.0f) {
    const float b = lm + MACHINE_MTPA_START_K * w;
    w = fd_minf(w, c / (b * b * b));
  }
  for (int n = 0; n < MACHINE_MTPA_HALLEY; ++n) {
    const float v = w + lm;
    const float v2 = v * v;
    const float f = w * v * v2 - c;
    const float df = v2 * (4.0f * w + lm);
    const float d2f = 6.0f * v * (v + w);
    /* > 0 near the root (2 F'^2 dominates); a 0 (no magnet, w = 0) or a
     * NaN keeps w */
    const float den = 2.0f * df * df - f * d2f;
    w = den > 0.0f ? fd_maxf(w - 2.0f * f * df / den, 0.0f) : w;
  }
  const float r = 1.0f / dl; /* one division for both currents */
  const float iq = sqrtf(w * (w + lm)) * fabsf(r);
  return (dq_t){-w * r, t < 0.0f ? -iq : iq};
}

dq_t machine_voltage_ss(const machine_t *m, dq_t i, float we) {
  const dq_t l = machine_flux(m, i);
  return (dq_t){m->rs * i.d - we * l.q, m->rs * i.q + we * l.d};
}
