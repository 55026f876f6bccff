/*
 * rls_ab.c - recursive least squares of the DFC amplitudes (see rls_ab.h;
 * Fabbri 2022 (4.51)-(4.57)).
 */
#include "rls_ab.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"

FD_COLD bool rls_ab_init(rls_ab_t *k, const rls_ab_cfg_t *cfg) {
  const rls_ab_cfg_t *c = cfg;
  if (!(c->lambda > 0.0f && c->lambda <= 1.0f && c->r > 0.0f && fd_isfinite(c->r) &&
        c->p_min > 0.0f && c->p_max >= c->p_min && fd_isfinite(c->p_max))) {
    return false;
  }
  k->cfg = *c;
  rls_ab_reset(k, 0.0f, 0.0f, c->p_max);
  return true;
}

void rls_ab_reset(rls_ab_t *k, float a0, float b0, float p0) {
  k->x[0] = a0;
  k->x[1] = b0;
  const float p = fd_clampf(p0, k->cfg.p_min, k->cfg.p_max);
  k->p[0] = p;
  k->p[1] = 0.0f;
  k->p[2] = p;
}

bool rls_ab_update(rls_ab_t *k, float g_al, float g_be, float c2, float s2, const float *km) {
  if (!(fd_isfinite(g_al) && fd_isfinite(g_be) && fd_isfinite(c2) && fd_isfinite(s2))) {
    return false;
  }
  /* H of (4.54): rows (alpha, beta), columns (a, b) */
  const float c4 = c2 * c2 - s2 * s2, s4 = 2.0f * s2 * c2;
  float h12 = c4, h22 = s4;
  /* mut: rls_sequentiality_map_ignored */
  if (km != NULL) { /* the 4theta term as the sequentiality maps it (dfc_vec_t.k) */
    h12 = km[0] * c4 - km[1] * s4;
    h22 = km[3] * s4 - km[2] * c4;
  }
  const float h11 = -c2, h21 = s2;
  const float p11 = k->p[0], p12 = k->p[1], p22 = k->p[2];
  /* M = P H^T (2x2), S = H M + R */
  const float m11 = p11 * h11 + p12 * h12, m12 = p11 * h21 + p12 * h22;
  const float m21 = p12 * h11 + p22 * h12, m22 = p12 * h21 + p22 * h22;
  const float s11 = h11 * m11 + h12 * m21 + k->cfg.r;
  const float s12 = h11 * m12 + h12 * m22;
  const float s22 = h21 * m12 + h22 * m22 + k->cfg.r;
  const float det = s11 * s22 - s12 * s12;
  if (!(det > 0.0f) || !fd_isfinite(det)) {
    return false;
  }
  const float id = 1.0f / det;
  const float i11 = s22 * id, i12 = -s12 * id, i22 = s11 * id;
  /* K = M S^-1 (4.55) */
  const float k11 = m11 * i11 + m12 * i12, k12 = m11 * i12 + m12 * i22;
  const float k21 = m21 * i11 + m22 * i12, k22 = m21 * i12 + m22 * i22;
  /* innovation (4.56) and correction (4.57) */
  const float e1 = g_al - (h11 * k->x[0] + h12 * k->x[1]);
  const float e2 = g_be - (h21 * k->x[0] + h22 * k->x[1]);
  k->x[0] += k11 * e1 + k12 * e2;
  k->x[1] += k21 * e1 + k22 * e2;
  /* P = (P - K H P) / lambda = (P - K M^T) / lambda, symmetric */
  const float il = 1.0f / k->cfg.lambda;
  float n11 = (p11 - (k11 * m11 + k12 * m12)) * il;
  const float n12 = (p12 - 0.5f * (k11 * m21 + k12 * m22 + k21 * m11 + k22 * m12)) * il;
  float n22 = (p22 - (k21 * m21 + k22 * m22)) * il;
  n11 = fd_clampf(n11, k->cfg.p_min, k->cfg.p_max);
  n22 = fd_clampf(n22, k->cfg.p_min, k->cfg.p_max);
  /* |p12| < sqrt(p11 p22): positive definite after the limits */
  const float lim = 0.999f * sqrtf(n11 * n22);
  k->p[0] = n11;
  k->p[1] = fd_clampf(n12, -lim, lim);
  k->p[2] = n22;
  return true;
}
