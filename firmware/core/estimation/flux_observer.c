/*
 * flux_observer.c - hybrid stator-flux observer with one-step prediction,
 * Rubino 2020, Fig. 3 and eqs. (19)-(20).
 */
#include "estimation/flux_observer.h"

#include <math.h>
#include <string.h>

#include "math/fast_trig.h"
#include "math/fd_math.h"

/* The integrator, its angles and the polar form inlined into each entry point (as calls
 * they cost the SPM laws 43 instructions a period, PIL). */
#if defined(__GNUC__)
#define FO_INLINE static inline __attribute__((always_inline))
#else
#define FO_INLINE static inline
#endif

/* Amplitude and unit vector of a flux vector; a vanishing vector gets the
 * identity direction (theta = 0). */
FO_INLINE float flux_observer_polar(ab_t x, sincos_t *sc) {
  const float a = sqrtf(x.alpha * x.alpha + x.beta * x.beta);
  if (a > 1e-9f) {
    sc->c = x.alpha / a;
    sc->s = x.beta / a;
  } else {
    sc->c = 1.0f;
    sc->s = 0.0f;
  }
  return a;
}

FD_COLD int flux_observer_init(flux_observer_t *o, const flux_observer_cfg_t *cfg) {
  memset(o, 0, sizeof(*o));
  const flux_observer_cfg_t *c = cfg;
  if (!(c->machine != NULL && fd_isfinite(c->ts) && c->ts > 0.0f && fd_isfinite(c->omega_c) &&
        c->omega_c >= 0.0f && fd_isfinite(c->omega_s_bw) && c->omega_s_bw > 0.0f)) {
    return -1;
  }
  o->cfg = *cfg;
  o->alpha_s = -expm1f(-c->omega_s_bw * c->ts);
  flux_observer_reset(o);
  return 0;
}

void flux_observer_reset(flux_observer_t *o) {
  o->lambda_hat.alpha = 0.0f;
  o->lambda_hat.beta = 0.0f;
  o->theta_s_prev = 0.0f;
  o->omega_s = 0.0f;
  o->started = 0;
  o->angles_started = 0;
}

void flux_observer_update(flux_observer_t *o, ab_t i, ab_t i_next, ab_t v, float theta_r,
                          float omega_r, flux_observer_out_t *out) {
  flux_observer_update_sc(o, i, i_next, v, theta_r, frames_sincos(theta_r), omega_r, out);
}

FO_INLINE void fo_core(flux_observer_t *o, ab_t i, ab_t i_next, ab_t v, ab_t lcm,
                       flux_observer_out_t *out) {
  const flux_observer_cfg_t *c = &o->cfg;
  const machine_t *m = c->machine;
  if (!o->started) {
    o->lambda_hat = lcm;
  }
  const ab_t lh = o->lambda_hat;

  out->lambda = lh;
  out->lambda_cm = lcm;
  out->lambda_s = flux_observer_polar(lh, &out->sc_s);

  /* Fig. 3: back-EMF (resistive drop averaged over the period) plus the
   * current-model correction omega_c (lambda_cm - lambda_hat), then the one-step
   * prediction, Rubino 2020, eqs. (19)-(20) */
  const float hr = 0.5f * m->rs;
  ab_t e;
  e.alpha = v.alpha - hr * (i.alpha + i_next.alpha) + c->omega_c * (lcm.alpha - lh.alpha);
  e.beta = v.beta - hr * (i.beta + i_next.beta) + c->omega_c * (lcm.beta - lh.beta);
  ab_t ln;
  ln.alpha = lh.alpha + c->ts * e.alpha;
  ln.beta = lh.beta + c->ts * e.beta;
  out->lambda_next = ln;
  out->lambda_s_next = flux_observer_polar(ln, &out->sc_s_next);

  /* stator-flux frame currents and torque, eq. (16) */
  out->i_dqs = frames_park(i, out->sc_s);
  out->torque = 1.5f * m->pole_pairs * out->lambda_s * out->i_dqs.q;

  o->lambda_hat = ln;
  o->started = 1;
}

FO_INLINE void fo_angles(flux_observer_t *o, float theta_r, float omega_r,
                         flux_observer_out_t *out) {
  const flux_observer_cfg_t *c = &o->cfg;
  out->theta_s = fd_atan2f(out->sc_s.s, out->sc_s.c);
  /* flux-frame speed: filtered derivative of theta_s */
  if (!o->angles_started) {
    o->omega_s = fd_isfinite(omega_r) ? omega_r : 0.0f;
  } else {
    const float raw = frames_wrap_pi(out->theta_s - o->theta_s_prev) / c->ts;
    o->omega_s += o->alpha_s * (raw - o->omega_s);
  }
  o->angles_started = 1;
  o->theta_s_prev = out->theta_s;
  out->omega_s = o->omega_s;
  /* load angle, Rubino 2020, eq. (9)-c */
  out->delta = frames_wrap_pi(out->theta_s - theta_r);
}

void flux_observer_update_sc(flux_observer_t *o, ab_t i, ab_t i_next, ab_t v, float theta_r,
                             sincos_t scr, float omega_r, flux_observer_out_t *out) {
  const machine_t *m = o->cfg.machine;
  /* current model, Rubino 2020, eq. (2) in (alpha, beta) */
  const float ls = machine_ls(m);
  ab_t lcm;
  lcm.alpha = ls * i.alpha + m->lambda_m * scr.c;
  lcm.beta = ls * i.beta + m->lambda_m * scr.s;
  fo_core(o, i, i_next, v, lcm, out);
  fo_angles(o, theta_r, omega_r, out);
}

void flux_observer_update_cm(flux_observer_t *o, ab_t i, ab_t i_next, ab_t v, ab_t lcm,
                             flux_observer_out_t *out) {
  fo_core(o, i, i_next, v, lcm, out);
  /* the angles: flux_observer_angles() */
  out->theta_s = 0.0f;
  out->omega_s = 0.0f;
  out->delta = 0.0f;
}

void flux_observer_angles(flux_observer_t *o, float theta_r, float omega_r,
                          flux_observer_out_t *out) {
  fo_angles(o, theta_r, omega_r, out);
}
