/*
 * current_predictor.c - model predictive current estimator (MPE),
 * Rubino 2020, eq. (21).
 */
#include "estimation/current_predictor.h"

#include <math.h>
#include <string.h>

#include "math/fd_math.h"

FD_COLD int current_predictor_init(current_predictor_t *p, const current_predictor_cfg_t *cfg) {
  memset(p, 0, sizeof(*p));
  if (cfg->machine == NULL ||
      (cfg->mode != CURRENT_PREDICTOR_EXACT && cfg->mode != CURRENT_PREDICTOR_EQ21)) {
    return -1;
  }
  if (spm_discrete_init(&p->disc, cfg->machine->rs, machine_ls(cfg->machine), cfg->ts) != 0) {
    return -1;
  }
  p->cfg = *cfg;
  return 0;
}

void current_predictor_reset(current_predictor_t *p) {
  spm_discrete_reset(&p->disc);
}

void current_predictor_speed(const current_predictor_t *p, float omega_r,
                             current_predictor_speed_t *w) {
  w->omega_r = omega_r;
  w->coef = spm_discrete_coef_rot(&p->disc, omega_r, &w->rot, &w->half);
}

ab_t current_predictor_step_sc(const current_predictor_t *p, const current_predictor_speed_t *w,
                               ab_t i, ab_t v, sincos_t sc_r) {
  const spm_discrete_t *m = &p->disc;
  ab_t y;
  /* Rubino 2020, eq. (21): homogeneous and voltage terms, (alpha, beta) = (9)-b */
  y.alpha = m->ks * i.alpha + m->b_ab * v.alpha;
  y.beta = m->ks * i.beta + m->b_ab * v.beta;

  const float wl = w->omega_r * p->cfg.machine->lambda_m;
  if (p->cfg.mode == CURRENT_PREDICTOR_EQ21) {
    /* - j omega_r lambda_m e^{j theta_r}, held at tau over the period, eq. (21) */
    y.alpha += m->b_ab * (wl * sc_r.s);
    y.beta += m->b_ab * (-wl * sc_r.c);
  } else {
    /* Rubino 2020, eqs. (8), (10)-(15) in the rotor frame (9)-a: u = (0, -omega_r lambda_m)
     * is constant there; rotate the response back at theta_r(tau+1). */
    dq_t di;
    di.d = w->coef.b_xy * (-wl);
    di.q = w->coef.b_xx * (-wl);
    const ab_t d_ab = frames_park_inv(di, frames_sincos_add(sc_r, w->rot));
    y.alpha += d_ab.alpha;
    y.beta += d_ab.beta;
  }
  return y;
}

ab_t current_predictor_step(const current_predictor_t *p, ab_t i, ab_t v, float theta_r,
                            float omega_r) {
  current_predictor_speed_t w;
  current_predictor_speed(p, omega_r, &w);
  return current_predictor_step_sc(p, &w, i, v, frames_sincos(theta_r));
}
