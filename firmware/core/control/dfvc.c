/*
 * dfvc.c - DB-DFVC and PI-DFVC for SPM machines, Rubino 2020, Figs. 2-7.
 */
#include "control/dfvc.h"

#include <math.h>
#include <string.h>

#include "math/fd_math.h"

#define DFVC_2PI 6.28318530717959f
#define DFVC_DEG 0.0174532925199433f

FD_COLD void dfvc_cfg_defaults(dfvc_cfg_t *cfg, const machine_t *machine) {
  memset(cfg, 0, sizeof(*cfg));
  cfg->machine = machine;
  cfg->ts = 62.5e-6f; /* Rubino 2020, section IV: 16 kHz */
  /* section III.B, IV */
  cfg->omega_c = 125.0f;
  cfg->delta_max = 80.0f * DFVC_DEG;
  cfg->v_sd_max = 60.0f;
  cfg->pi_bw_flux = DFVC_2PI * 1000.0f;
  cfg->pi_bw_iqs = DFVC_2PI * 1000.0f;
  /* open in the paper: see dfvc.h */
  cfg->omega_s_bw = 1000.0f;
  cfg->i_max = 2.5f * 1.41421356f;
  cfg->lambda_min = 0.2f * machine->lambda_m;
  cfg->lambda_collapse = 0.5f * cfg->lambda_min;
  cfg->v_margin = 0.95f;
  cfg->mpe_mode = CURRENT_PREDICTOR_EXACT;
  cfg->omega_delta_mode = DFVC_OMEGA_DELTA_TARGET;
  cfg->rot_advance = 0.5f;
}

FD_COLD int dfvc_init(dfvc_t *c, const dfvc_cfg_t *cfg) {
  memset(c, 0, sizeof(*c));
  c->cfg = *cfg;
  const dfvc_cfg_t *k = cfg;
  if (!(fd_isfinite(k->rot_advance) && k->rot_advance >= 0.0f && k->rot_advance <= 1.0f &&
        fd_isfinite(k->lambda_collapse) && k->lambda_collapse >= 0.0f &&
        (k->omega_delta_mode == DFVC_OMEGA_DELTA_TARGET ||
         k->omega_delta_mode == DFVC_OMEGA_DELTA_OBSERVED))) {
    return -1;
  }
  const machine_t *m = k->machine;
  const flux_observer_cfg_t oc = {m, k->ts, k->omega_c, k->omega_s_bw};
  const current_predictor_cfg_t pc = {m, k->ts, k->mpe_mode};
  const dfvc_refs_cfg_t rc = {m, k->i_max, k->delta_max, k->lambda_min, k->v_margin};
  const dfvc_deadbeat_cfg_t dc = {m, k->ts, k->v_sd_max};
  const dfvc_pi_cfg_t ic = {m, k->ts, k->pi_bw_flux, k->pi_bw_iqs, k->v_sd_max};
  if (flux_observer_init(&c->obs, &oc) != 0 || current_predictor_init(&c->mpe, &pc) != 0 ||
      dfvc_refs_init(&c->refs, &rc) != 0 || dfvc_deadbeat_init(&c->db, &dc) != 0 ||
      dfvc_pi_init(&c->pi, &ic) != 0) {
    return -1;
  }
  /* rot_advance exactly 0.5 (<= and >= : no float ==) */
  c->adv_half = k->rot_advance >= 0.5f && k->rot_advance <= 0.5f;
  c->last_law = DFVC_LAW_DEADBEAT;
  return 0;
}

void dfvc_reset(dfvc_t *c) {
  flux_observer_reset(&c->obs);
  current_predictor_reset(&c->mpe);
  dfvc_refs_reset(&c->refs);
  dfvc_deadbeat_reset(&c->db);
  dfvc_pi_reset(&c->pi);
  c->last_law = DFVC_LAW_DEADBEAT;
}

/* A fault's outputs: all zero (no voltage), the telemetry too. Out of
 * line: off the period's path. */
static FD_NOINLINE void dfvc_out_fault(dfvc_out_t *out, law_telemetry_t *tm, uint32_t fault) {
  memset(out, 0, sizeof(*out));
  memset(tm, 0, sizeof(*tm));
  out->fault = fault;
}

/* 0 for a finite vector, NaN otherwise (fd_zero_if_finite) */
static inline float dfvc_zero_if_finite_ab(ab_t x) {
  return fd_zero_if_finite(x.alpha) + fd_zero_if_finite(x.beta);
}

static int dfvc_inputs_ok(dfvc_law_t law, const dfvc_in_t *in) {
  const float z = dfvc_zero_if_finite_ab(in->i_ab) + dfvc_zero_if_finite_ab(in->v_applied) +
                  fd_zero_if_finite(in->theta_e) + fd_zero_if_finite(in->omega_e) +
                  fd_zero_if_finite(in->v_lin) + fd_zero_if_finite(in->torque_ref) +
                  fd_zero_if_finite(in->flux_ref);
  return (law == DFVC_LAW_DEADBEAT || law == DFVC_LAW_PI) && fd_isfinite(z);
}

/* delta(tau+1) = theta_s(tau+1) - theta_r(tau+1), wrapped; theta_r(tau+1)
 * = theta_r + omega_r Ts (dfvc.h) */
static float dfvc_delta_next(const dfvc_in_t *in, const flux_observer_out_t *o, float ts) {
  const float theta_r1 = in->theta_e + in->omega_e * ts;
  return frames_wrap_pi(fd_atan2f(o->sc_s_next.s, o->sc_s_next.c) - theta_r1);
}

void dfvc_step(dfvc_t *c, dfvc_law_t law, const dfvc_in_t *in, dfvc_out_t *out,
               law_telemetry_t *tm) {
  const dfvc_cfg_t *k = &c->cfg;
  /* every field of *out is written below (no zeroing per ISR); the fault
   * paths clear it */
  if (!dfvc_inputs_ok(law, in)) {
    dfvc_out_fault(out, tm, DFVC_FAULT_INPUT);
    return;
  }

  /* One sin/cos of the rotor angle and one of the rotation over a period
   * (with the model's coefficients) per ISR; the other angles' sin/cos are
   * products of these unit vectors. */
  current_predictor_speed_t w;
  current_predictor_speed(&c->mpe, in->omega_e, &w);
  const sincos_t scr = frames_sincos(in->theta_e);
  const sincos_t scr1 = frames_sincos_add(scr, w.rot); /* theta_r(tau+1) */

  /* MPE, eq. (21): current at tau+1 */
  const ab_t i1 = current_predictor_step_sc(&c->mpe, &w, in->i_ab, in->v_applied, scr);

  /* stator flux at tau and its prediction at tau+1, Fig. 3, eqs. (19)-(20) */
  flux_observer_out_t o;
  flux_observer_update_sc(&c->obs, in->i_ab, i1, in->v_applied, in->theta_e, scr, in->omega_e, &o);
  const dq_t i1_dqs = frames_park(i1, o.sc_s_next);
  const sincos_t sc_delta1 = frames_sincos_sub(o.sc_s_next, scr1);

  /* references, Fig. 5, eqs. (22)-(26), from the quantities at tau; the
   * current limit (25) at tau+2 from the MPE prediction (dfvc_refs.h) */
  const dfvc_refs_in_t ri = {in->torque_ref, in->flux_ref, in->omega_e, in->v_lin,
                             o.i_dqs.d,      o.i_dqs.q,    i1_dqs,      sc_delta1};
  dfvc_refs_out_t r;
  dfvc_refs_update(&c->refs, &ri, &r);

  /* the linear range of the modulator */
  const float v_max = fd_maxf(in->v_lin, 0.0f);
  dq_t v_dqs;
  uint32_t lim = r.limits;
  if (law == DFVC_LAW_DEADBEAT) {
    dfvc_deadbeat_in_t di;
    di.lambda_ref = r.lambda_ref;
    di.iqs_ref = r.iqs_ref;
    di.lambda_s_next = o.lambda_s_next;
    di.i_dqs_next = i1_dqs;
    di.omega_r = in->omega_e;
    /* delta(tau+1) as an angle (an atan2) only where it is read: the
     * observed rate, and the target's branch beyond |delta| = pi/2 (the
     * asin of dfvc_deadbeat_omega_delta_target_sc; 0 is not read there) */
    const float delta1 = (k->omega_delta_mode != DFVC_OMEGA_DELTA_TARGET || !(sc_delta1.c >= 0.0f))
                             ? dfvc_delta_next(in, &o, k->ts)
                             : 0.0f;
    di.omega_delta =
        (k->omega_delta_mode == DFVC_OMEGA_DELTA_TARGET)
            ? dfvc_deadbeat_omega_delta_target_sc(&c->db, r.iqs_ref, i1_dqs.q, delta1, sc_delta1)
            : frames_wrap_pi(delta1 - o.delta) / k->ts;
    di.v_max = v_max;
    dfvc_deadbeat_out_t dout;
    /* Rubino 2020, eqs. (28), (29), (33) */
    dfvc_deadbeat_step(&c->db, &di, &dout);
    v_dqs = dout.v_dqs;
    lim |= ((dout.sat & DFVC_DEADBEAT_SAT_D) ? DFVC_LIMIT_VD : 0u) |
           ((dout.sat & DFVC_DEADBEAT_SAT_Q) ? DFVC_LIMIT_VQ : 0u);
  } else {
    if (c->last_law != DFVC_LAW_PI) {
      dfvc_pi_reset(&c->pi);
    }
    dfvc_pi_in_t pin;
    pin.lambda_ref = r.lambda_ref;
    pin.iqs_ref = r.iqs_ref;
    pin.lambda_s = o.lambda_s;
    pin.i_dqs = o.i_dqs;
    pin.omega_r = in->omega_e;
    pin.omega_delta = o.omega_s - in->omega_e;
    pin.v_max = v_max;
    dfvc_pi_out_t pout;
    /* Rubino 2020, section IV.7 */
    dfvc_pi_step(&c->pi, &pin, &pout);
    v_dqs = pout.v_dqs;
    lim |= ((pout.sat & DFVC_PI_SAT_D) ? DFVC_LIMIT_VD : 0u) |
           ((pout.sat & DFVC_PI_SAT_Q) ? DFVC_LIMIT_VQ : 0u);
  }
  c->last_law = law;

  /* (ds, qs) -> (alpha, beta) at the predicted flux angle theta_s(tau+1)
   * (Rubino 2020, Fig. 7), advanced by rot_advance * omega_r * Ts */
  /* at the default half period this is the predictor's half-angle
   * evaluation: (0.5 omega_r) Ts and 0.5 (omega_r Ts) are the same float */
  const sincos_t adv = c->adv_half ? w.half : frames_sincos(k->rot_advance * in->omega_e * k->ts);
  sincos_t scv;
  scv.c = o.sc_s_next.c * adv.c - o.sc_s_next.s * adv.s;
  scv.s = o.sc_s_next.s * adv.c + o.sc_s_next.c * adv.s;
  const ab_t v_ab = frames_park_inv(v_dqs, scv);

  /* double-step prediction (section IV.B): current at tau+2 under v_ab */
  const ab_t i2 = current_predictor_step_sc(&c->mpe, &w, i1, v_ab, scr1);

  const float z = dfvc_zero_if_finite_ab(v_ab) + dfvc_zero_if_finite_ab(i2) +
                  dfvc_zero_if_finite_ab(o.lambda_next) + fd_zero_if_finite(r.lambda_ref) +
                  fd_zero_if_finite(r.iqs_ref);
  if (!fd_isfinite(z)) {
    dfvc_reset(c);
    dfvc_out_fault(out, tm, DFVC_FAULT_STATE);
    return;
  }

  out->v_ab_ref = v_ab;
  out->i_ab_mid.alpha = 0.5f * (i1.alpha + i2.alpha);
  out->i_ab_mid.beta = 0.5f * (i1.beta + i2.beta);
  out->i_qs_pred = i1_dqs.q;
  out->i_dq_r = frames_park(in->i_ab, scr);
  out->torque_min = r.torque_min;
  out->torque_max = r.torque_max;
  out->v_dqs = v_dqs;
  out->limits = lim;
  /* the telemetry where the caller publishes it (no copy) */
  tm->flux = o.lambda_s;
  tm->flux_ref = r.lambda_ref;
  tm->delta = o.delta; /* the load-angle limit's: taken every period */
  tm->lam_d = 0.0f;
  tm->lam_q = 0.0f;
  tm->delta_lazy = false;
  tm->i_ds = o.i_dqs.d;
  tm->i_qs = o.i_dqs.q;
  tm->i_qs_ref = r.iqs_ref;
  tm->torque = o.torque;
  {
    const float ea = o.lambda.alpha - o.lambda_cm.alpha, eb = o.lambda.beta - o.lambda_cm.beta;
    tm->obs_err = sqrtf(ea * ea + eb * eb);
  }
  out->fault = (o.lambda_s < k->lambda_collapse) ? DFVC_FAULT_FLUX_COLLAPSE : 0u;
}
