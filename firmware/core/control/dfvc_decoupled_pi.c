/*
 * dfvc_decoupled_pi.c - flux and torque-current regulators of the decoupled DFVC,
 * Varatharajan 2022, eqs. (26)-(28).
 */
#include "control/dfvc_decoupled_pi.h"

#include <math.h>
#include <string.h>

#include "math/fd_math.h"

FD_COLD int dfvc_decoupled_pi_init(dfvc_decoupled_pi_t *c, const dfvc_decoupled_pi_cfg_t *cfg) {
  memset(c, 0, sizeof(*c));
  const dfvc_decoupled_pi_cfg_t *k = cfg;
  if (!(fd_isfinite(k->ts) && k->ts > 0.0f && fd_isfinite(k->omega) && k->omega > 0.0f &&
        fd_isfinite(k->v_f_max) && k->v_f_max > 0.0f)) {
    return -1;
  }
  c->cfg = *cfg;
  /* eq. (28) in discrete form (dfvc_decoupled_pi.h): double pole at exp(-Omega Ts) */
  const float p = expf(-k->omega * k->ts);
  /* mut: dfvc_decoupled_kp_half */
  c->kp = (1.0f - p * p) / k->ts;
  c->ki = (1.0f - p) * (1.0f - p) / (k->ts * k->ts);
  c->kits = c->ki * k->ts;
  return 0;
}

void dfvc_decoupled_pi_reset(dfvc_decoupled_pi_t *c) {
  c->integ_f = 0.0f;
  c->integ_t = 0.0f;
  c->u_t_prev = 0.0f;
}

/* |x| <= lim; *sat set when clipped */
static float dfvc_decoupled_pi_clip(float x, float lim, int *sat) {
  *sat = (x > lim) || (x < -lim);
  return fd_clampf(x, -lim, lim);
}

void dfvc_decoupled_pi_step(dfvc_decoupled_pi_t *c, const dfvc_decoupled_pi_in_t *in,
                            dfvc_decoupled_pi_out_t *out) {
  const dfvc_decoupled_pi_cfg_t *k = &c->cfg;
  const float kits = c->kits;
  /* the controlled variables at tau+1 (dfvc_decoupled_pi.h, delay) */
  const float itau_pred = in->i_ft.q + k->ts * c->u_t_prev;
  const float e_f = in->lambda_ref - in->lambda_next;
  const float e_t = in->itau_ref - itau_pred;
  const float int_f = c->integ_f + kits * e_f;
  const float int_t = c->integ_t + kits * e_t;
  /* PI of (26)/(27), gains (28) */
  const dq_t u = {c->kp * e_f + int_f, c->kp * e_t + int_t};
  /* Varatharajan 2022, eq. (27): v = Rs i + J omega lambda + T_hat u */
  const dq_t tu = sfo_transform(in->g, u);
  const float ff_f = in->rs * in->i_ft.d;
  const float ff_t = in->rs * in->i_ft.q + in->omega_r * in->lambda_next;
  const float vmax = fd_maxf(in->v_max, 0.0f);
  int sf = 0;
  int st = 0;
  const float vf_raw = ff_f + tu.d;
  const float vf = dfvc_decoupled_pi_clip(vf_raw, fd_minf(k->v_f_max, vmax), &sf);
  const float vt_lim = sqrtf(fd_maxf(vmax * vmax - vf * vf, 0.0f));
  const float vt_raw = ff_t + tu.q;
  const float vt = dfvc_decoupled_pi_clip(vt_raw, vt_lim, &st);
  /* conditional integration: not while the error pushes further into the
   * limit (the tau row of T has the sign of 1/b > 0) */
  if (!(sf && (vf_raw - vf) * e_f > 0.0f)) {
    c->integ_f = int_f;
  }
  if (!(st && (vt_raw - vt) * e_t > 0.0f)) {
    c->integ_t = int_t;
  }
  /* the virtual inputs actually applied (21) */
  const dq_t ua = sfo_transform_inv(in->g, (dq_t){vf - ff_f, vt - ff_t});
  c->u_t_prev = ua.q;
  out->v_ft = (dq_t){vf, vt};
  out->u = ua;
  out->sat = (sf ? DFVC_DECOUPLED_PI_SAT_F : 0u) | (st ? DFVC_DECOUPLED_PI_SAT_T : 0u);
}
