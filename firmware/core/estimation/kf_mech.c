/*
 * kf_mech.c - the Kalman filter on the rotor's mechanics (see kf_mech.h;
 * Fabbri 2022, (4.15)-(4.21), (4.46)-(4.49)).
 */
#include "kf_mech.h"

#include "math/fast_trig.h"
#include "math/fd_math.h"
#include "math/frames.h"

enum { P11, P12, P13, P22, P23, P33 };

static bool finite_nonneg(float v) {
  return fd_isfinite(v) && v >= 0.0f;
}

FD_COLD bool kf_mech_init(kf_mech_t *k, const kf_mech_cfg_t *cfg) {
  const kf_mech_cfg_t *c = cfg;
  if (!(c->ts > 0.0f && fd_isfinite(c->ts) && c->inertia > 0.0f && fd_isfinite(c->inertia) &&
        c->pole_pairs > 0.0f && fd_isfinite(c->pole_pairs) && finite_nonneg(c->friction) &&
        finite_nonneg(c->q[0]) && finite_nonneg(c->q[1]) && finite_nonneg(c->q[2]))) {
    return false;
  }
  k->cfg = *c;
  k->f11 = 1.0f - c->ts * c->friction / c->inertia;
  k->g1 = c->ts * c->pole_pairs / c->inertia;
  k->f13 = -k->g1;
  const float p0[3] = {0.0f, 0.0f, 0.0f};
  kf_mech_reset(k, 0.0f, 0.0f, p0);
  return true;
}

void kf_mech_reset(kf_mech_t *k, float theta, float omega, const float p0[3]) {
  k->x[0] = omega;
  k->x[1] = frames_wrap_pi(theta);
  k->x[2] = 0.0f;
  k->p[P11] = p0[0];
  k->p[P12] = 0.0f;
  k->p[P13] = 0.0f;
  k->p[P22] = p0[1];
  k->p[P23] = 0.0f;
  k->p[P33] = p0[2];
}

void kf_mech_predict(kf_mech_t *k, float t_e) {
  const float t = k->cfg.ts, f11 = k->f11, f13 = k->f13;
  float *x = k->x, *p = k->p;
  /* x- = F x + G u (4.47), the angle with the speed before the step */
  const float w = x[0];
  x[0] = f11 * w + f13 * x[2] + k->g1 * t_e;
  x[1] = frames_wrap_pi(x[1] + t * w);
  /* P- = F P F^T + Q, F = [f11 0 f13; t 1 0; 0 0 1]: written out on the
   * upper triangle */
  const float a11 = p[P11], a12 = p[P12], a13 = p[P13], a22 = p[P22], a23 = p[P23], a33 = p[P33];
  const float r1_1 = f11 * a11 + f13 * a13; /* row 1 of F P */
  const float r1_2 = f11 * a12 + f13 * a23;
  const float r1_3 = f11 * a13 + f13 * a33;
  const float r2_1 = t * a11 + a12; /* row 2 of F P */
  const float r2_2 = t * a12 + a22;
  const float r2_3 = t * a13 + a23;
  p[P11] = r1_1 * f11 + r1_3 * f13 + k->cfg.q[0];
  p[P12] = r1_1 * t + r1_2;
  p[P13] = r1_3;
  p[P22] = r2_1 * t + r2_2 + k->cfg.q[1];
  p[P23] = r2_3;
  p[P33] = a33 + k->cfg.q[2];
}

bool kf_mech_update(kf_mech_t *k, float theta_meas, float r) {
  if (!fd_isfinite(theta_meas) || !(r > 0.0f) || !fd_isfinite(r)) {
    return false;
  }
  float *x = k->x, *p = k->p;
  const float s = p[P22] + r; /* H P H^T + R */
  const float inv_s = 1.0f / s;
  /* K = P H^T / s: the second column of P */
  const float k1 = p[P12] * inv_s, k2 = p[P22] * inv_s, k3 = p[P23] * inv_s;
  const float innov = frames_wrap_pi(theta_meas - x[1]); /* (4.20), wrapped */
  x[0] += k1 * innov;
  x[1] = frames_wrap_pi(x[1] + k2 * innov);
  /* mut: kf_load_gain_dropped */
  x[2] += k3 * innov;
  /* Joseph form: (I - K H) P (I - K H)^T + K R K^T. With H = [0 1 0],
   * A = I - K H has column 2 = -K (+1 on the diagonal); A P A^T expands to
   * P - K c^T - c K^T + s K K^T with c = P H^T, and + R K K^T - s K K^T
   * ... written so: P+ = P - K c^T - c K^T + (p22 + r) K K^T */
  const float c1 = p[P12], c2 = p[P22], c3 = p[P23];
  p[P11] += -2.0f * k1 * c1 + s * k1 * k1;
  p[P12] += -k1 * c2 - c1 * k2 + s * k1 * k2;
  p[P13] += -k1 * c3 - c1 * k3 + s * k1 * k3;
  /* mut: kf_joseph_term_dropped */
  p[P22] += -2.0f * k2 * c2 + s * k2 * k2;
  p[P23] += -k2 * c3 - c2 * k3 + s * k2 * k3;
  p[P33] += -2.0f * k3 * c3 + s * k3 * k3;
  return true;
}

bool kf_mech_update_ekf(kf_mech_t *k, float g_al, float g_be, float a, float b, const float km[4],
                        float r) {
  if (!(fd_isfinite(g_al) && fd_isfinite(g_be) && fd_isfinite(a) && fd_isfinite(b)) ||
      !(r > 0.0f) || !fd_isfinite(r)) {
    return false;
  }
  float *x = k->x, *p = k->p;
  float s2, c2;
  fd_sincosf(2.0f * x[1], &s2, &c2);
  const float c4 = c2 * c2 - s2 * s2, s4 = 2.0f * s2 * c2;
  /* the 4theta term as the signal vector carries it: q = K (cos 4theta,
   * -sin 4theta) (dfc.h: the map the IVD applies; K = I at standstill,
   * where this is (4.35)); h = (-a cos 2theta + b q_r, a sin 2theta - b q_i) */
  /* mut: ekf_sequentiality_map_ignored.1 */
  const float qr = km[0] * c4 - km[1] * s4, qi = km[2] * c4 - km[3] * s4;
  /* innovation (4.41) and the theta column of H (4.36) */
  const float e1 = g_al - (-a * c2 + b * qr), e2 = g_be - (a * s2 - b * qi);
  /* mut: ekf_sequentiality_map_ignored.2 */
  const float h1 = 2.0f * a * s2 - 4.0f * b * (km[0] * s4 + km[1] * c4);
  /* mut: ekf_jacobian_b_sign */
  /* mut: ekf_sequentiality_map_ignored.3 */
  const float h2 = 2.0f * a * c2 + 4.0f * b * (km[2] * s4 + km[3] * c4);
  /* P H^T = c h^T with c = P's theta column; S = (h h^T) p22 + r I (4.37) */
  const float c1 = p[P12], cc2 = p[P22], c3 = p[P23];
  const float s11 = h1 * h1 * cc2 + r, s12 = h1 * h2 * cc2, s22 = h2 * h2 * cc2 + r;
  const float det = s11 * s22 - s12 * s12;
  if (!(det > 0.0f) || !fd_isfinite(det)) {
    return false;
  }
  const float id = 1.0f / det;
  /* K = c h^T S^-1 = c v^T, v = S^-1 h */
  const float v1 = (s22 * h1 - s12 * h2) * id, v2 = (s11 * h2 - s12 * h1) * id;
  const float nu = v1 * e1 + v2 * e2; /* v^T e */
  x[0] += c1 * nu;
  x[1] = frames_wrap_pi(x[1] + cc2 * nu);
  x[2] += c3 * nu;
  /* Joseph form (4.39): with K = c v^T and H = h e_theta^T,
   * P+ = P - c g c^T - c g c^T + (g^2 p22 + r |v|^2) c c^T, g = v^T h */
  const float g = v1 * h1 + v2 * h2;
  const float w = -2.0f * g + g * g * cc2 + r * (v1 * v1 + v2 * v2);
  p[P11] += w * c1 * c1;
  p[P12] += w * c1 * cc2;
  p[P13] += w * c1 * c3;
  p[P22] += w * cc2 * cc2;
  p[P23] += w * cc2 * c3;
  p[P33] += w * c3 * c3;
  return true;
}
