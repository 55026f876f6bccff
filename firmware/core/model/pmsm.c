/*
 * pmsm.c - linear PMSM in the rotor frame (d on the magnet flux).
 */
#include "model/pmsm.h"

#include <math.h>

#include "math/fd_math.h"

dq_t pmsm_flux(const pmsm_params_t *m, dq_t i) {
  dq_t l;
  l.d = m->ld * i.d + m->lambda_m;
  l.q = m->lq * i.q;
  return l;
}

/* T = 3/2 p (lambda_d iq - lambda_q id) = 3/2 p (lambda_m iq + (Ld - Lq) id iq) */
float pmsm_torque(const pmsm_params_t *m, dq_t i) {
  const dq_t l = pmsm_flux(m, i);
  return 1.5f * m->pole_pairs * (l.d * i.q - l.q * i.d);
}

/* id = 0: T = 3/2 p lambda_m iq. Zero when the machine has no magnet. */
float pmsm_iq_for_torque(const pmsm_params_t *m, float t) {
  const float k = 1.5f * m->pole_pairs * m->lambda_m;
  return (fabsf(k) > 1e-12f && fd_isfinite(t)) ? t / k : 0.0f;
}

/* Steady state (di/dt = 0): v = Rs i + we J lambda,
 * vd = Rs id - we lambda_q, vq = Rs iq + we lambda_d. */
dq_t pmsm_voltage_ss(const pmsm_params_t *m, dq_t i, float we) {
  const dq_t l = pmsm_flux(m, i);
  dq_t v;
  v.d = m->rs * i.d - we * l.q;
  v.q = m->rs * i.q + we * l.d;
  return v;
}
