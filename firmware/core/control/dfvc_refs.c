/*
 * dfvc_refs.c - DFVC flux and torque-current references, Rubino 2020,
 * Fig. 5 and eqs. (22)-(26).
 */
#include "control/dfvc_refs.h"

#include <math.h>
#include <string.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"

#define DFVC_REFS_HALF_PI 1.57079632679490f
#define DFVC_REFS_W_MIN   1.0f /* floor of |omega_r| in (23) [rad/s] */

static int dfvc_refs_pos(float x) {
  return fd_isfinite(x) && x > 0.0f;
}

int dfvc_refs_init(dfvc_refs_t *r, const dfvc_refs_cfg_t *cfg) {
  memset(r, 0, sizeof(*r));
  const dfvc_refs_cfg_t *c = cfg;
  if (!(c->machine != NULL && dfvc_refs_pos(c->machine->lambda_m) && dfvc_refs_pos(c->i_max) &&
        dfvc_refs_pos(c->delta_max) && c->delta_max <= DFVC_REFS_HALF_PI &&
        dfvc_refs_pos(c->lambda_min) && dfvc_refs_pos(c->v_margin) && c->v_margin <= 1.0f)) {
    return -1;
  }
  r->cfg = *cfg;
  dfvc_refs_reset(r);
  return 0;
}

void dfvc_refs_reset(dfvc_refs_t *r) {
  /* Rubino 2020, eq. (26) */
  float sd;
  float cd;
  fd_sincosf(r->cfg.delta_max, &sd, &cd);
  r->iqs_max_delta = r->cfg.machine->lambda_m / machine_ls(r->cfg.machine) * sd;
  r->torque_mtpa_max = 1.5f * r->cfg.machine->pole_pairs * r->cfg.machine->lambda_m * r->cfg.i_max;
}

float dfvc_refs_lambda_mtpa(const dfvc_refs_t *r, float torque_ref) {
  const dfvc_refs_cfg_t *c = &r->cfg;
  const float t = fd_minf(fabsf(torque_ref), r->torque_mtpa_max);
  /* Rubino 2020, eq. (22) */
  const machine_t *m = c->machine;
  const float x = machine_ls(m) * t / (m->pole_pairs * m->lambda_m * m->lambda_m);
  return m->lambda_m * sqrtf(1.0f + (4.0f / 9.0f) * x * x);
}

float dfvc_refs_lambda_vlim(const dfvc_refs_t *r, float v_lin, float omega_r, float i_ds,
                            float i_qs) {
  const dfvc_refs_cfg_t *c = &r->cfg;
  const float vmax = fd_maxf(v_lin, 0.0f) * c->v_margin;
  const float rd = c->machine->rs * i_ds;
  const float rad = vmax * vmax - rd * rd;
  if (rad <= 0.0f) {
    return 0.0f;
  }
  const float sgn = (omega_r < 0.0f) ? -1.0f : 1.0f;
  /* Rubino 2020, eq. (23), with omega_s replaced by omega_r */
  const float num = sqrtf(rad) - c->machine->rs * i_qs * sgn;
  return fd_maxf(num, 0.0f) / fd_maxf(fabsf(omega_r), DFVC_REFS_W_MIN);
}

void dfvc_refs_update(const dfvc_refs_t *r, const dfvc_refs_in_t *in, dfvc_refs_out_t *out) {
  const dfvc_refs_cfg_t *c = &r->cfg;
  unsigned lim = 0u;

  /* Fig. 5: flux reference */
  out->lambda_mtpa =
      (in->lambda_override > 0.0f) ? in->lambda_override : dfvc_refs_lambda_mtpa(r, in->torque_ref);
  out->lambda_vlim = dfvc_refs_lambda_vlim(r, in->v_lin, in->omega_r, in->i_ds, in->i_qs);
  float lref = out->lambda_mtpa;
  if (out->lambda_vlim < lref) {
    lref = out->lambda_vlim;
    lim |= DFVC_REFS_FLUX_VLIM;
  }
  if (lref < c->lambda_min) {
    lref = c->lambda_min;
    lim |= DFVC_REFS_FLUX_MIN;
  }
  out->lambda_ref = lref;

  /* Rubino 2020, eq. (24) */
  out->iqs_unlimited = in->torque_ref / (1.5f * c->machine->pole_pairs * lref);
  /* Rubino 2020, eq. (25) */
  const float rad = c->i_max * c->i_max - in->i_ds * in->i_ds;
  out->iqs_max_i = (rad > 0.0f) ? sqrtf(rad) : 0.0f;
  /* Rubino 2020, eq. (26) */
  out->iqs_max_delta = r->iqs_max_delta;

  float iq = out->iqs_unlimited;
  const float a = fabsf(iq);
  if (a > out->iqs_max_i) {
    iq = copysignf(out->iqs_max_i, iq);
    lim |= DFVC_REFS_IQS_IMAX;
  }
  if (fabsf(iq) > out->iqs_max_delta) {
    iq = copysignf(out->iqs_max_delta, iq);
    lim |= DFVC_REFS_IQS_DELTA;
  }
  out->iqs_ref = iq;
  out->torque_max =
      1.5f * c->machine->pole_pairs * lref * fd_minf(out->iqs_max_i, out->iqs_max_delta);
  out->torque_min = -out->torque_max;
  out->limits = lim;
}
