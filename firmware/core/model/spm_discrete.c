/*
 * spm_discrete.c - exact discretisation of the SPM current dynamics
 * (Rubino 2020, eqs. (10)-(15)).
 */
#include "model/spm_discrete.h"

#include <math.h>
#include <string.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"

static int spm_discrete_valid(float x) {
  return fd_isfinite(x) && (x > 0.0f);
}

void spm_discrete_reset(spm_discrete_t *m) {
  /* Rubino 2020, eq. (12) */
  m->fs = m->rs / m->ls;
  m->one_minus_k = -expm1f(-m->fs * m->ts);
  m->ks = 1.0f - m->one_minus_k;
  /* eq. (15) with omega_xy = 0: b_xx = (1 - k_s)/Rs, b_xy = 0 */
  m->b_ab = m->one_minus_k / m->rs;
}

FD_COLD int spm_discrete_init(spm_discrete_t *m, float rs, float ls, float ts) {
  memset(m, 0, sizeof(*m));
  if (!spm_discrete_valid(rs) || !spm_discrete_valid(ls) || !spm_discrete_valid(ts)) {
    return -1;
  }
  m->rs = rs;
  m->ls = ls;
  m->ts = ts;
  spm_discrete_reset(m);
  return 0;
}

spm_discrete_coef_t spm_discrete_coef(const spm_discrete_t *m, float omega_xy) {
  sincos_t rot;
  sincos_t half;
  return spm_discrete_coef_rot(m, omega_xy, &rot, &half);
}

spm_discrete_coef_t spm_discrete_coef_rot(const spm_discrete_t *m, float omega_xy, sincos_t *rot,
                                          sincos_t *half) {
  spm_discrete_coef_t c;
  const float phi = omega_xy * m->ts; /* eq. (12) */
  /* one sin/cos evaluation at phi/2: sin phi = 2 sh ch, 1 - cos phi = 2 sh^2 */
  float sh;
  float ch;
  fd_sincosf(0.5f * phi, &sh, &ch);
  half->s = sh;
  half->c = ch;
  const float vers = 2.0f * sh * sh;
  /* Rubino 2020, eq. (14) */
  rot->c = 1.0f - vers;
  rot->s = 2.0f * sh * ch;
  c.a_xx = m->ks * rot->c;
  c.a_xy = m->ks * rot->s;
  /* 1 - a_xx without cancellation: (1 - k) + k (1 - cos phi) */
  const float one_minus_axx = m->one_minus_k + m->ks * vers;
  /* Rubino 2020, eq. (15); 1/Rs * f/(f^2 + w^2) written as 1/(Ls (f^2 + w^2)) */
  const float g = 1.0f / (m->ls * (m->fs * m->fs + omega_xy * omega_xy));
  c.b_xx = g * (m->fs * one_minus_axx + omega_xy * c.a_xy);
  c.b_xy = g * (omega_xy * one_minus_axx - m->fs * c.a_xy);
  return c;
}

dq_t spm_discrete_step(const spm_discrete_coef_t *c, dq_t i, dq_t u) {
  /* Rubino 2020, eq. (10) with the structure (13) */
  dq_t y;
  y.d = c->a_xx * i.d + c->a_xy * i.q + c->b_xx * u.d + c->b_xy * u.q;
  y.q = -c->a_xy * i.d + c->a_xx * i.q - c->b_xy * u.d + c->b_xx * u.q;
  return y;
}
