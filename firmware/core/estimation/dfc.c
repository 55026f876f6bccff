/*
 * dfc.c - Direct Flux Control position with Iterative Vector Decoupling
 * (see dfc.h; Fabbri 2022, (2.101), (3.6)-(3.16), (3.76), (3.100)).
 */
#include "dfc.h"

#include <stddef.h>

#include "math/cordic_q31.h"
#include "math/fd_math.h"
#include "math/frames.h"

#define DFC_SQRT3_INV 0.57735026918962576f
#define DFC_PHI_MAX   1.0f /* rad/A: a phase shift model beyond this is a typo */

FD_COLD int dfc_check(const dfc_cfg_t *c) {
  if ((unsigned)c->method > (unsigned)DFC_FULL_IVD) {
    return DFC_ERR_METHOD;
  }
  if (!fd_isfinite(c->a) || !fd_isfinite(c->b) || !(fabsf(c->a) > 0.0f)) {
    return DFC_ERR_A;
  }
  if (c->iterations > DFC_ITER_MAX) {
    return DFC_ERR_ITER;
  }
  if (!(fabsf(c->phi_a) <= DFC_PHI_MAX) || !(fabsf(c->phi_b) <= DFC_PHI_MAX)) {
    return DFC_ERR_PHI;
  }
  /* Theorem 1: |Delta_k| -> 0 iff |p| < 1/2 */
  /* mut: dfc_theorem1_unchecked */
  if ((c->method == DFC_IVD || c->method == DFC_FULL_IVD) && !(fabsf(c->b) < 0.5f * fabsf(c->a))) {
    return DFC_ERR_P;
  }
  return DFC_OK;
}

FD_COLD const char *dfc_strerror(int err) {
  switch (err) {
  case DFC_OK:
    return "ok";
  case DFC_ERR_METHOD:
    return "unknown DFC method";
  case DFC_ERR_A:
    return "the DFC amplitude a must be finite and non-zero, b finite";
  case DFC_ERR_P:
    return "IVD needs |p| = |b/a| < 1/2 (Theorem 1: no convergence otherwise)";
  case DFC_ERR_ITER:
    return "too many IVD iterations";
  case DFC_ERR_PHI:
    return "Full IVD phase shifts must be finite, within 1 rad/A";
  default:
    return "?";
  }
}

void dfc_signals_reset(dfc_signals_t *s) {
  for (int x = 0; x < 3; ++x) {
    s->g[x] = 0.0f;
    s->t[x] = 0.0f;
  }
  s->have = 0u;
  s->last = 0u;
}

bool dfc_signals_push(dfc_signals_t *s, uint8_t tv, float v_before, float v_after, float v_dc,
                      float t) {
  const int x = tv == 1u ? 0 : (tv == 3u ? 1 : (tv == 5u ? 2 : -1));
  if (x < 0 || !fd_isfinite(v_before) || !fd_isfinite(v_after) || !(v_dc > 0.0f) ||
      !fd_isfinite(v_dc)) {
    return false;
  }
  /* (2.96)-(2.101): the virtual star point steps by v_dc / 3 */
  s->g[x] = (v_after - v_before) / v_dc - (1.0f / 3.0f);
  s->t[x] = t;
  s->have |= (uint8_t)(1u << x);
  s->last = (uint8_t)x;
  return true;
}

void dfc_vec_plain(const float g[3], dfc_vec_t *v) {
  v->al = (2.0f * g[0] - g[1] - g[2]) * (1.0f / 3.0f);
  v->be = (g[1] - g[2]) * DFC_SQRT3_INV;
  v->k[0] = 1.0f;
  v->k[1] = 0.0f;
  v->k[2] = 0.0f;
  v->k[3] = 1.0f;
}

/* cos, sin of a small angle (|x| < 0.5 rad: within 3e-5) by their series
 * to the fourth / fifth order: no libm in the ISR */
static inline __attribute__((always_inline)) void dfc_turn(float x, float *c, float *s) {
  const float x2 = x * x;
  *c = 1.0f - 0.5f * x2 * (1.0f - x2 * (1.0f / 12.0f));
  *s = x * (1.0f - x2 * (1.0f / 6.0f) * (1.0f - x2 * (1.0f / 20.0f)));
}

void dfc_signals_vector(const dfc_signals_t *s, float w2, dfc_vec_t *v) {
  /* phase axes c_x of the amplitude-invariant Clarke transform */
  static const float cx[3][2] = {{1.0f, 0.0f}, {-0.5f, 0.86602540f}, {-0.5f, -0.86602540f}};
  /* the newest component is not turned (phi = 0: d = e = c_x): its terms
   * c_x c_x^T of A and B are constants (c_x0^2, c_x0 c_x1, c_x1^2), the
   * sums start from them and the loop runs over the two held ones only */
  static const float cc[3][3] = {
      {1.0f, 0.0f, 0.0f}, {0.25f, -0.43301270f, 0.75000000f}, {0.25f, 0.43301270f, 0.75000000f}};
  const unsigned l = s->last;
  const float t_new = s->t[l];
  float a11 = cc[l][0], a12 = cc[l][1], a22 = cc[l][2];
  float r1 = cx[l][0] * s->g[l], r2 = cx[l][1] * s->g[l];
  float b11 = a11, b12 = a12, b21 = a12, b22 = a22;
  for (unsigned j = 1u; j < 3u; ++j) {
    const unsigned x = l + j < 3u ? l + j : l + j - 3u;
    /* phi = 2 omega_e (t_new - t_x): the 2theta term was e^{+j phi} ahead,
     * so Gamma_x projects it on c_x e^{-j phi} (d); the 4theta term was
     * e^{-j2phi} behind: on c_x e^{+j2phi} (e) */
    const float phi = w2 * (t_new - s->t[x]);
    float co, si;
    /* mut: dfc_sequentiality_sign */
    dfc_turn(-phi, &co, &si);
    /* e^{j2phi} = conj(e^{-j phi})^2: the double angle, three products
     * (more accurate than the series at 2 phi: its error is 2 x^6 / 720
     * against 64 x^6 / 720) */
    const float co2 = co * co - si * si, si2 = -2.0f * co * si;
    const float d1 = cx[x][0] * co - cx[x][1] * si, d2 = cx[x][0] * si + cx[x][1] * co;
    const float e1 = cx[x][0] * co2 - cx[x][1] * si2, e2 = cx[x][0] * si2 + cx[x][1] * co2;
    a11 += d1 * d1;
    a12 += d1 * d2;
    a22 += d2 * d2;
    r1 += d1 * s->g[x];
    r2 += d2 * s->g[x];
    b11 += d1 * e1;
    b12 += d1 * e2;
    b21 += d2 * e1;
    b22 += d2 * e2;
  }
  const float det = a11 * a22 - a12 * a12; /* 9/4 for phi = 0 */
  const float k = det > 0.5f ? 1.0f / det : 0.0f;
  v->al = (a22 * r1 - a12 * r2) * k;
  v->be = (a11 * r2 - a12 * r1) * k;
  /* K = A^-1 B, conjugated: C K C */
  const float k11 = (a22 * b11 - a12 * b21) * k, k12 = (a22 * b12 - a12 * b22) * k;
  const float k21 = (a11 * b21 - a12 * b11) * k, k22 = (a11 * b22 - a12 * b12) * k;
  v->k[0] = k11;
  v->k[1] = -k12;
  v->k[2] = -k21;
  v->k[3] = k22;
}

/* u <- w / |w|; false when |w| is zero or not finite */
static inline bool dfc_normalise(float wr, float wi, float *ur, float *ui) {
  const float m2 = wr * wr + wi * wi;
  if (!(m2 > 1e-30f) || !fd_isfinite(m2)) {
    return false;
  }
  const float k = 1.0f / sqrtf(m2);
  *ur = wr * k;
  *ui = wi * k;
  return true;
}

FD_NOINLINE bool dfc_ivd_step(float zr, float zi, float p, const float k[4], const float rb[2],
                              const float ra[2], float *ur, float *ui) {
  /* e^{-j4theta_{k-1}} = conj(u)^2; times r_b = e^{-j phi_b} (3.100), the
   * Full IVD's (the plain IVD's r_b, r_a are 1: no turn); the sequentiality
   * map K */
  float tr = *ur * *ur - *ui * *ui, ti = -2.0f * *ur * *ui;
  if (rb != NULL) {
    const float sr = tr;
    tr = sr * rb[0] - ti * rb[1];
    ti = sr * rb[1] + ti * rb[0];
  }
  const float qr = k[0] * tr + k[1] * ti, qi = k[2] * tr + k[3] * ti;
  float vr, vi;
  /* mut: dfc_ivd_no_b_term */
  if (!dfc_normalise(zr + p * qr, zi + p * qi, &vr, &vi)) {
    return false;
  }
  /* minus phi_a: times r_a = e^{-j phi_a} */
  if (ra != NULL) {
    *ur = vr * ra[0] - vi * ra[1];
    *ui = vr * ra[1] + vi * ra[0];
  } else {
    *ur = vr;
    *ui = vi;
  }
  return true;
}

/* Clarke (amplitude invariant) of three components */
static inline void dfc_clarke(const float x[3], float *al, float *be) {
  *al = (2.0f * x[0] - x[1] - x[2]) * (1.0f / 3.0f);
  *be = (x[1] - x[2]) * DFC_SQRT3_INV;
}

/* The standard DFC's / IVD's / Full IVD's estimate (3.8) / (3.98) (from_raw:
 * from zeta, trace[0..1] the raw one) or, from the start *ur, *ui, the
 * iterations (3.76) / (3.100) alone (c->iterations of them, IVD methods):
 * dfc_vector2 and dfc_ivd_from share it, inlined: each call of the ISR
 * (the warm start's dfc_ivd_from every period) without the other's branch. */
static inline __attribute__((always_inline)) bool ivd_run(const dfc_cfg_t *c, const dfc_vec_t *v,
                                                          float i_q, bool from_raw, float *ur,
                                                          float *ui, float *trace) {
  const float inv_a = 1.0f / c->a;
  const float zr = -v->al * inv_a, zi = v->be * inv_a; /* zeta = e^{j2th} - p e^{-j4th} */
  const bool full = c->method == DFC_FULL_IVD;
  float ra[2], rb[2];                         /* the Full IVD's turns e^{-j phi_a}, e^{-j phi_b} */
  const float *turn_a = NULL, *turn_b = NULL; /* (the plain IVD: none) */
  if (full) {
    const sincos_t pa = frames_sincos(c->phi_a * i_q), pb = frames_sincos(c->phi_b * i_q);
    ra[0] = pa.c;
    /* mut: dfc_full_ivd_phi_a_sign */
    ra[1] = -pa.s;
    rb[0] = pb.c;
    rb[1] = -pb.s;
    turn_a = ra;
    turn_b = rb;
  }
  if (from_raw) { /* (3.8) / (3.98): the raw estimate */
    if (!dfc_normalise(zr, zi, ur, ui)) {
      return false;
    }
    if (turn_a != NULL) {
      const float r = *ur * turn_a[0] - *ui * turn_a[1];
      *ui = *ur * turn_a[1] + *ui * turn_a[0];
      *ur = r;
    }
    if (trace != NULL) {
      trace[0] = *ur;
      trace[1] = *ui;
    }
  }
  const uint32_t n = (c->method == DFC_IVD || full)
                         ? (c->iterations < DFC_ITER_MAX ? c->iterations : DFC_ITER_MAX)
                         : 0u;
  const float p = c->b * inv_a;
  for (uint32_t k = 1u; k <= n; ++k) { /* (3.76) / (3.100) */
    if (!dfc_ivd_step(zr, zi, p, v->k, turn_b, turn_a, ur, ui)) {
      return false;
    }
    if (trace != NULL) {
      trace[(size_t)2 * k] = *ur;
      trace[(size_t)2 * k + 1u] = *ui;
    }
  }
  return true;
}

bool dfc_vector2(const dfc_cfg_t *c, const float g[3], const dfc_vec_t *v, float i_q, float *c2,
                 float *s2, float *trace) {
  float ur = 1.0f, ui = 0.0f;
  bool ok;
  *c2 = 1.0f;
  *s2 = 0.0f;
  if (c->method == DFC_INVERSE) {
    /* (3.15): kappa_x = sum L_Sigma / L_Sigma,x = 1 / (Gamma_x / v_dc + 1/3);
     * (3.16): its Clarke vector turns as e^{-j2theta}. On the components
     * at the newest one's instant: v's vector (the held components turned,
     * sequentiality) with the three's mean; g itself when v is plain. On
     * the raw held components (one period old on average) the angle lagged
     * by w_e ts: -2.7 degrees at 790 rad/s (docs/machines.md). */
    const float g0 = (g[0] + g[1] + g[2]) * (1.0f / 3.0f);
    const float hb = 0.86602540f * v->be;
    const float gs[3] = {g0 + v->al, g0 - 0.5f * v->al + hb, g0 - 0.5f * v->al - hb};
    float k[3], ka, kb;
    for (int x = 0; x < 3; ++x) {
      /* mut: inverse_dfc_on_raw_components */
      const float d = gs[x] + (1.0f / 3.0f);
      k[x] = fabsf(d) > 1e-6f ? 1.0f / d : 0.0f;
    }
    dfc_clarke(k, &ka, &kb);
    const float sg = c->a > 0.0f ? 1.0f : -1.0f;
    ok = dfc_normalise(sg * ka, -sg * kb, &ur, &ui);
    if (ok && trace != NULL) {
      trace[0] = ur;
      trace[1] = ui;
    }
  } else {
    ok = ivd_run(c, v, i_q, true, &ur, &ui, trace);
  }
  if (!ok) {
    return false;
  }
  *c2 = ur;
  *s2 = ui;
  return true;
}

bool dfc_ivd_from(const dfc_cfg_t *c, const dfc_vec_t *v, float i_q, float *c2, float *s2,
                  float *trace) {
  if (!(c->method == DFC_IVD || c->method == DFC_FULL_IVD)) {
    return false;
  }
  /* mut: ivd_from_ignores_start */
  float ur = *c2, ui = *s2;
  if (!ivd_run(c, v, i_q, false, &ur, &ui, trace)) {
    return false;
  }
  *c2 = ur;
  *s2 = ui;
  return true;
}

float dfc_angle2(const dfc_cfg_t *c, const float g[3], float i_q, bool *ok) {
  float c2, s2;
  dfc_vec_t v;
  dfc_vec_plain(g, &v);
  *ok = dfc_vector2(c, g, &v, i_q, &c2, &s2, NULL);
  return fd_cordic_atan2f(s2, c2);
}
