/*
 * machine.c - the machine_t interface: the linear machine here, the
 * flux-map machine by dispatch to flux_map.c.
 */
#include "model/machine.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"

/* Newton steps of the MTPA inversion of the linear machine
 * (machine_mtpa_current): from the starting point there, 5 steps reach
 * float resolution over the whole range (torque within 2e-7 relative for
 * c / lambda_m^4 from 1e-12 to 1e12; tests/core/test_machine.c checks the
 * residual). */
#define MACHINE_MTPA_NEWTON 5

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
 * Newton from above approaches monotonically; no square root per step,
 * one division (issue 24 point 8: the FOC's worst ISR; this was Newton on
 * T(I) through mtpa_at, two roots and two divisions a step). Start: the
 * smaller of the two upper bounds F(w) >= w lambda_m^3 - c and
 * F(w) >= w^4 - c, i.e. w0 = min(c / lambda_m^3, c^(1/4)). Iterating on w,
 * not on w + lambda_m, keeps a nearly isotropic machine's small w
 * exact. */
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
    w = fd_minf(w, c / (lm * lm * lm));
  }
  for (int n = 0; n < MACHINE_MTPA_NEWTON; ++n) {
    const float v = w + lm;
    const float f = w * v * v * v - c;
    const float df = v * v * (4.0f * w + lm);
    w = df > 0.0f ? fd_maxf(w - f / df, 0.0f) : w;
  }
  const float iq = sqrtf(w * (w + lm)) / adl;
  return (dq_t){-w / dl, t < 0.0f ? -iq : iq};
}

dq_t machine_voltage_ss(const machine_t *m, dq_t i, float we) {
  const dq_t l = machine_flux(m, i);
  return (dq_t){m->rs * i.d - we * l.q, m->rs * i.q + we * l.d};
}
