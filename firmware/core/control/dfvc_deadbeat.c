/*
 * dfvc_deadbeat.c - deadbeat flux and i_qs laws, Rubino 2020, eqs. (28)-(33).
 */
#include "control/dfvc_deadbeat.h"

#include <math.h>
#include <string.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"

static int dfvc_deadbeat_pos(float x) {
  return fd_isfinite(x) && x > 0.0f;
}

FD_COLD int dfvc_deadbeat_init(dfvc_deadbeat_t *db, const dfvc_deadbeat_cfg_t *cfg) {
  memset(db, 0, sizeof(*db));
  const dfvc_deadbeat_cfg_t *c = cfg;
  if (!(c->machine != NULL && dfvc_deadbeat_pos(c->machine->lambda_m) && dfvc_deadbeat_pos(c->ts) &&
        dfvc_deadbeat_pos(c->v_sd_max))) {
    return -1;
  }
  db->cfg = *cfg;
  dfvc_deadbeat_reset(db);
  return 0;
}

void dfvc_deadbeat_reset(dfvc_deadbeat_t *db) {
  db->inv_ts = 1.0f / db->cfg.ts;
  db->ls_ts = machine_ls(db->cfg.machine) / db->cfg.ts;
}

float dfvc_deadbeat_omega_delta_target(const dfvc_deadbeat_t *db, float iqs_ref, float iqs_next,
                                       float delta_next) {
  return dfvc_deadbeat_omega_delta_target_sc(db, iqs_ref, iqs_next, delta_next,
                                             frames_sincos(delta_next));
}

float dfvc_deadbeat_omega_delta_target_sc(const dfvc_deadbeat_t *db, float iqs_ref, float iqs_next,
                                          float delta_next, sincos_t sc_delta) {
  /* q_s row of Rubino 2020, eq. (16): Ls i_qs = lambda_m sin(delta), used
   * incrementally from the predicted state: sin(delta*) = sin(delta(t+1))
   * + Ls (i_qs* - i_qs(t+1)) / lambda_m. With exact parameters this is
   * asin(Ls i_qs* / lambda_m); with detuned ones the error scales the step
   * only and vanishes in steady state (no bias on v_qs). */
  const float sd = sc_delta.s;
  const float s =
      fd_clampf(sd + machine_ls(db->cfg.machine) * (iqs_ref - iqs_next) / db->cfg.machine->lambda_m,
                -1.0f, 1.0f);
  if (!(sc_delta.c >= 0.0f)) {
    /* |delta(t+1)| > pi/2, beyond the principal branch of asin */
    return frames_wrap_pi(fd_asinf(s) - delta_next) * db->inv_ts;
  }
  /* delta* - delta(t+1) = asin(s) - asin(sin delta(t+1)) as the angle of
   * e^{j asin(s)} e^{-j asin(sd)}: one atan2, no sin -> asin round trip,
   * and exactly 0 in steady state (s = sd) */
  const float qs = sqrtf((1.0f - s) * (1.0f + s));
  const float qd = sqrtf(fd_maxf((1.0f - sd) * (1.0f + sd), 0.0f));
  return fd_atan2f(s * qd - sd * qs, qs * qd + s * sd) * db->inv_ts;
}

void dfvc_deadbeat_step(const dfvc_deadbeat_t *db, const dfvc_deadbeat_in_t *in,
                        dfvc_deadbeat_out_t *out) {
  const dfvc_deadbeat_cfg_t *c = &db->cfg;
  const machine_t *m = c->machine;
  unsigned sat = 0u;

  /* Rubino 2020, eq. (29) */
  /* mut: deadbeat_no_rs_29 */
  const float vd = m->rs * in->i_dqs_next.d + (in->lambda_ref - in->lambda_s_next) * db->inv_ts;
  /* Rubino 2020, eq. (33) */
  /* mut: deadbeat_no_rs_33 */
  /* mut: deadbeat_no_omega_delta_33 */
  const float vq = m->rs * in->i_dqs_next.q + in->omega_delta * machine_ls(m) * in->i_dqs_next.d +
                   /* mut: deadbeat_emf_sign */
                   in->omega_r * in->lambda_s_next + db->ls_ts * (in->iqs_ref - in->i_dqs_next.q);
  out->v_dqs_raw.d = vd;
  out->v_dqs_raw.q = vq;

  const float vmax = fd_maxf(in->v_max, 0.0f);
  const float vd_max = fd_minf(c->v_sd_max, vmax);
  float vdl = vd;
  if (fabsf(vdl) > vd_max) {
    vdl = copysignf(vd_max, vdl);
    sat |= DFVC_DEADBEAT_SAT_D;
  }
  const float vq_max = sqrtf(fd_maxf(vmax * vmax - vdl * vdl, 0.0f));
  float vql = vq;
  if (fabsf(vql) > vq_max) {
    vql = copysignf(vq_max, vql);
    sat |= DFVC_DEADBEAT_SAT_Q;
  }
  out->v_dqs.d = vdl;
  out->v_dqs.q = vql;
  out->sat = sat;
}
