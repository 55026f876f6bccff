/*
 * sfo_model.c - stator-flux-frame quantities of a saturated machine,
 * Varatharajan 2022 eqs. (6), (7), (9), (10), (17), (22), (23).
 */
#include "model/sfo_model.h"

#include <math.h>

#include "math/fast_trig.h"

float sfo_line_angle(dq_t x, dq_t y) {
  const float c = x.d * y.q - x.q * y.d; /* |x||y| sin */
  const float d = x.d * y.d + x.q * y.q; /* |x||y| cos */
  return fd_atan2f(fabsf(c), fabsf(d));
}

sfo_gains_t sfo_gains(dq_t lambda, dq_t i, machine_ldq_t l) {
  const float l2 = lambda.d * lambda.d + lambda.q * lambda.q;
  if (!(l2 > 1e-12f)) {
    return (sfo_gains_t){0.0f, 0.0f};
  }
  /* Varatharajan 2022, eq. (22), b = lambda^T J i^a / lambda^2 */
  return (sfo_gains_t){sfo_gain_a(lambda, l),
                       sfo_mtpv_cross(lambda, sfo_aux_current(lambda, i, l)) / l2};
}

sfo_gains_t sfo_gains_sota(float lambda, sincos_t sc_delta, float l_app_d, float l_app_q,
                           float lambda_m) {
  const float k = (l_app_d - l_app_q) / (l_app_d * l_app_q);
  const float s2 = 2.0f * sc_delta.s * sc_delta.c;
  const float c2 = sc_delta.c * sc_delta.c - sc_delta.s * sc_delta.s;
  sfo_gains_t g;
  /* Varatharajan 2022, eq. (17), PM on +d (sfo_model.h): the PM term
   * -sin(delta) lambda_m / (lambda L_q) becomes cos(delta) lambda_m / (lambda L_d) */
  g.a = 0.5f * s2 * k;
  /* mut: sfo_sota_pm_sign */
  g.b = c2 * k + ((lambda > 1e-9f) ? sc_delta.c * lambda_m / (lambda * l_app_d) : 0.0f);
  return g;
}

void sfo_apparent(dq_t lambda_i, dq_t i, float lambda_m, float i_min, float l0_d, float l0_q,
                  float *l_d, float *l_q) {
  /* eq. (3): lambda = L(i) i + lambda_m */
  *l_d = (fabsf(i.d) > i_min) ? (lambda_i.d - lambda_m) / i.d : l0_d;
  *l_q = (fabsf(i.q) > i_min) ? lambda_i.q / i.q : l0_q;
}
