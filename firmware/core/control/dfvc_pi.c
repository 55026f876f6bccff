/*
 * dfvc_pi.c - PI-DFVC with feed-forward, Rubino 2020, section IV.7.
 */
#include "control/dfvc_pi.h"

#include <math.h>
#include <string.h>

#include "math/fd_math.h"

static int dfvc_pi_pos(float x) {
  return fd_isfinite(x) && x > 0.0f;
}

/* One PI step with limits [-lim, lim]; while pushed into a limit the
 * integral tracks `track`; it is bounded to the output range minus ff. */
static float dfvc_pi_axis(float *integ, float kp, float ki, float ts, float err, float ff,
                          float lim, float track, int *sat) {
  const float u = kp * err + *integ + ff;
  const int hi = u > lim;
  const int lo = u < -lim;
  if ((hi && err > 0.0f) || (lo && err < 0.0f)) {
    *integ = track;
  } else {
    *integ += ki * ts * err;
  }
  *integ = fd_minf(fd_maxf(*integ, -lim - ff), lim - ff);
  float y = kp * err + *integ + ff;
  *sat = 0;
  if (y > lim) {
    y = lim;
    *sat = 1;
  } else if (y < -lim) {
    y = -lim;
    *sat = 1;
  }
  return y;
}

FD_COLD int dfvc_pi_init(dfvc_pi_t *c, const dfvc_pi_cfg_t *cfg) {
  memset(c, 0, sizeof(*c));
  const dfvc_pi_cfg_t *k = cfg;
  if (!(k->machine != NULL && dfvc_pi_pos(k->ts) && dfvc_pi_pos(k->bw_flux) &&
        dfvc_pi_pos(k->bw_iqs) && dfvc_pi_pos(k->v_sd_max))) {
    return -1;
  }
  c->cfg = *cfg;
  /* flux: plant 1/s after ff_d; integral zero at a quarter of the crossover */
  c->kp_flux = k->bw_flux;
  c->ki_flux = 0.25f * k->bw_flux * k->bw_flux;
  /* i_qs: plant 1/(Ls s + Rs), pole-zero cancellation */
  c->kp_iqs = k->bw_iqs * machine_ls(k->machine);
  c->ki_iqs = k->bw_iqs * k->machine->rs;
  dfvc_pi_reset(c);
  return 0;
}

void dfvc_pi_reset(dfvc_pi_t *c) {
  c->integ_d = 0.0f;
  c->integ_q = 0.0f;
}

void dfvc_pi_step(dfvc_pi_t *c, const dfvc_pi_in_t *in, dfvc_pi_out_t *out) {
  const dfvc_pi_cfg_t *k = &c->cfg;
  const float vmax = fd_maxf(in->v_max, 0.0f);
  int sd = 0;
  int sq = 0;

  /* flux loop on the d_s equation of Rubino 2020, eq. (16) */
  const float vd_max = fd_minf(k->v_sd_max, vmax);
  const machine_t *m = k->machine;
  const float ff_d = m->rs * in->i_dqs.d;
  const float vd = dfvc_pi_axis(&c->integ_d, c->kp_flux, c->ki_flux, k->ts,
                                in->lambda_ref - in->lambda_s, ff_d, vd_max, 0.0f, &sd);

  /* i_qs loop on Rubino 2020, eq. (32) */
  const float vq_max = sqrtf(fd_maxf(vmax * vmax - vd * vd, 0.0f));
  const float ff_q = in->omega_r * in->lambda_s + in->omega_delta * machine_ls(m) * in->i_dqs.d;
  const float vq = dfvc_pi_axis(&c->integ_q, c->kp_iqs, c->ki_iqs, k->ts, in->iqs_ref - in->i_dqs.q,
                                ff_q, vq_max, m->rs * in->i_dqs.q, &sq);

  out->v_dqs.d = vd;
  out->v_dqs.q = vq;
  out->sat = (sd ? DFVC_PI_SAT_D : 0u) | (sq ? DFVC_PI_SAT_Q : 0u);
}
