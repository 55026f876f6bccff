/*
 * dfvc_refs.c - DFVC flux and torque-current references, Rubino 2020,
 * Fig. 5 and eqs. (22)-(26).
 */
#include "control/dfvc_refs.h"

#include <math.h>
#include <string.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"

#if defined(__GNUC__)
#define DFVC_REFS_INLINE static inline __attribute__((always_inline))
#else
#define DFVC_REFS_INLINE static inline
#endif

#define DFVC_REFS_HALF_PI 1.57079632679490f
#define DFVC_REFS_W_MIN   1.0f /* floor of |omega_r| in (23) [rad/s] */

static int dfvc_refs_pos(float x) {
  return fd_isfinite(x) && x > 0.0f;
}

FD_COLD int dfvc_refs_init(dfvc_refs_t *r, const dfvc_refs_cfg_t *cfg) {
  memset(r, 0, sizeof(*r));
  const dfvc_refs_cfg_t *c = cfg;
  if (!(c->machine != NULL && dfvc_refs_pos(c->machine->lambda_m) && dfvc_refs_pos(c->i_max) &&
        dfvc_refs_pos(c->delta_max) && c->delta_max <= DFVC_REFS_HALF_PI &&
        dfvc_refs_pos(c->lambda_min) && dfvc_refs_pos(c->v_margin) && c->v_margin <= 1.0f)) {
    return -1;
  }
  /* mut: i_max_plus10pct */
  r->cfg = *cfg;
  dfvc_refs_reset(r);
  return 0;
}

void dfvc_refs_reset(dfvc_refs_t *r) {
  /* Rubino 2020, eq. (26) */
  float sd;
  float cd;
  /* mut: delta_max_65deg */
  fd_sincosf(r->cfg.delta_max, &sd, &cd);
  r->iqs_max_delta = r->cfg.machine->lambda_m / machine_ls(r->cfg.machine) * sd;
  r->cos_delta_max = cd;
  r->tan_delta_max = sd / fd_maxf(cd, 1e-3f); /* delta_max = pi/2: 1000 */
  r->torque_mtpa_max = 1.5f * r->cfg.machine->pole_pairs * r->cfg.machine->lambda_m * r->cfg.i_max;
  r->mtpa_t = NAN;
  r->mtpa_lambda = 0.0f;
}

float dfvc_refs_lambda_mtpa(const dfvc_refs_t *r, float torque_ref) {
  const dfvc_refs_cfg_t *c = &r->cfg;
  const float t = fd_minf(fabsf(torque_ref), r->torque_mtpa_max);
  /* Rubino 2020, eq. (22) */
  const machine_t *m = c->machine;
  const float x = machine_ls(m) * t / (m->pole_pairs * m->lambda_m * m->lambda_m);
  /* mut: mtpa_flux_2_3 */
  return m->lambda_m * sqrtf(1.0f + (4.0f / 9.0f) * x * x);
}

/* Rubino 2020, eq. (23), with omega_s replaced by omega_r: num / |omega_r|,
 * num = sqrt(v_max^2 - (Rs i_ds)^2) - Rs i_qs sgn(omega_r), 0 if negative;
 * vq = sqrt(v_max^2 - (Rs i_ds)^2) (< 0: none left), inv_w = 1 / |omega_r| */
static float dfvc_refs_vlim_of(const dfvc_refs_t *r, float vq, float inv_w, float omega_r,
                               float i_qs) {
  if (vq < 0.0f) {
    return 0.0f;
  }
  const float sgn = (omega_r < 0.0f) ? -1.0f : 1.0f;
  return fd_maxf(vq - r->cfg.machine->rs * i_qs * sgn, 0.0f) * inv_w;
}

/* sqrt(v_max^2 - (Rs i_ds)^2) of (23), or -1 when the radicand is not positive */
static float dfvc_refs_vq_avail(const dfvc_refs_t *r, float v_lin, float i_ds) {
  /* mut: v_margin_0_9 */
  const float vmax = fd_maxf(v_lin, 0.0f) * r->cfg.v_margin;
  const float rd = r->cfg.machine->rs * i_ds;
  const float rad = vmax * vmax - rd * rd;
  return (rad > 0.0f) ? sqrtf(rad) : -1.0f;
}

float dfvc_refs_lambda_vlim(const dfvc_refs_t *r, float v_lin, float omega_r, float i_ds,
                            float i_qs) {
  return dfvc_refs_vlim_of(r, dfvc_refs_vq_avail(r, v_lin, i_ds),
                           1.0f / fd_maxf(fabsf(omega_r), DFVC_REFS_W_MIN), omega_r, i_qs);
}

/* |i_qs*| clipped by (25) then (26), with the limit bits; inline (-Os
 * would call it: its two call sites are on the period's path) */
DFVC_REFS_INLINE float dfvc_refs_limit_iqs(const dfvc_refs_out_t *out, float iq, unsigned *lim) {
  if (fabsf(iq) > out->iqs_max_i) {
    iq = copysignf(out->iqs_max_i, iq);
    *lim |= DFVC_REFS_IQS_IMAX;
  }
  if (fabsf(iq) > out->iqs_max_delta) {
    iq = copysignf(out->iqs_max_delta, iq);
    *lim |= DFVC_REFS_IQS_DELTA;
  }
  return iq;
}

/* dfvc_refs_lambda_mtpa(r, t), computed again only when t changes (a NaN
 * on either side compares false: computed again) */
static float dfvc_refs_mtpa_cached(dfvc_refs_t *r, float t) {
  if (!(fabsf(t - r->mtpa_t) <= 0.0f)) {
    r->mtpa_lambda = dfvc_refs_lambda_mtpa(r, t);
    r->mtpa_t = t;
  }
  return r->mtpa_lambda;
}

void dfvc_refs_update(dfvc_refs_t *r, const dfvc_refs_in_t *in, dfvc_refs_out_t *out) {
  const dfvc_refs_cfg_t *c = &r->cfg;
  unsigned lim = 0u;

  /* Fig. 5: flux reference */
  out->lambda_mtpa =
      (in->lambda_override > 0.0f) ? in->lambda_override : dfvc_refs_mtpa_cached(r, in->torque_ref);
  const float vq = dfvc_refs_vq_avail(r, in->v_lin, in->i_ds);
  const float inv_w = 1.0f / fd_maxf(fabsf(in->omega_r), DFVC_REFS_W_MIN);
  out->lambda_vlim = dfvc_refs_vlim_of(r, vq, inv_w, in->omega_r, in->i_qs);
  float lref = out->lambda_mtpa;
  if (out->lambda_vlim < lref) {
    lref = out->lambda_vlim;
    lim |= DFVC_REFS_FLUX_VLIM;
  }
  if (lref < c->lambda_min) {
    lref = c->lambda_min;
    lim |= DFVC_REFS_FLUX_MIN;
  }

  /* Rubino 2020, eq. (25) at tau+2 (see dfvc_refs.h): the line
   * i_ds = a + k |i_qs|, k = tan|delta(tau+1)| <= tan(delta_max), through the
   * MPE current at tau+1, meets i_ds^2 + i_qs^2 = I_max^2 at
   * |i_qs| = (sqrt((1 + k^2) I_max^2 - a^2) - k a) / (1 + k^2); for
   * i_ds(tau+1) < 0 no more than the printed bound at i_ds(tau+1). */
  const float k = (in->sc_delta_next.c > r->cos_delta_max)
                      ? fabsf(in->sc_delta_next.s) / in->sc_delta_next.c
                      : r->tan_delta_max;
  const float a = in->i_dqs_next.d - k * fabsf(in->i_dqs_next.q);
  const float den = 1.0f + k * k;
  const float rad = den * c->i_max * c->i_max - a * a;
  const float q_line = (rad > 0.0f) ? fd_maxf((sqrtf(rad) - k * a) / den, 0.0f) : 0.0f;
  /* mut: refs_25_at_tau2_removed */
  if (in->i_dqs_next.d < 0.0f) {
    const float rad1 = c->i_max * c->i_max - in->i_dqs_next.d * in->i_dqs_next.d;
    out->iqs_max_i = fd_minf(q_line, (rad1 > 0.0f) ? sqrtf(rad1) : 0.0f);
  } else {
    out->iqs_max_i = q_line;
  }
  /* Rubino 2020, eq. (26) */
  out->iqs_max_delta = r->iqs_max_delta;

  /* Rubino 2020, eq. (24), limited by (25), (26) */
  float iu = in->torque_ref / (1.5f * c->machine->pole_pairs * lref);
  float iq = dfvc_refs_limit_iqs(out, iu, &lim);

  /* Rubino 2020, eq. (23) with the limited i_qs* (the q_s current at tau+2)
   * in place of i_qs(tau), when that gives less flux (see dfvc_refs.h);
   * then (24)-(26) again at the new flux */
  const float lv2 = dfvc_refs_vlim_of(r, vq, inv_w, in->omega_r, iq);
  /* mut: refs_23_at_iqs_ref_removed */
  if (lv2 < lref) {
    out->lambda_vlim = lv2;
    lref = lv2;
    lim = DFVC_REFS_FLUX_VLIM;
    if (lref < c->lambda_min) {
      lref = c->lambda_min;
      lim |= DFVC_REFS_FLUX_MIN;
    }
    iu = in->torque_ref / (1.5f * c->machine->pole_pairs * lref);
    iq = dfvc_refs_limit_iqs(out, iu, &lim);
  }
  out->lambda_ref = lref;
  out->iqs_unlimited = iu;
  out->iqs_ref = iq;
  out->torque_max =
      1.5f * c->machine->pole_pairs * lref * fd_minf(out->iqs_max_i, out->iqs_max_delta);
  out->torque_min = -out->torque_max;
  out->limits = lim;
}
