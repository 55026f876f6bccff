/*
 * drive_ctrl.c - the control laws behind one interface.
 *
 * FOC: rotor-frame PI current control with decoupling (the papers'
 * baseline). Torque mode uses i_d = 0 (SPM; for IPM this is not MTPA).
 * The voltage computed from the samples at k acts over [k+1, k+2): the
 * inverse Park uses the angle advanced by 1.5 periods, the centre of that
 * interval.
 *
 * PI-DFVC and DB-DFVC: control/dfvc.h (Rubino 2020), an SPM law: the
 * controller's inductance estimate is L_s = L_d (L_d = L_q for SPM).
 *
 * All laws: predictive dead-time compensation (Rubino 2020, Fig. 8) with
 * the currents expected over the period the duties act.
 */
#include "drive_ctrl.h"

#include <math.h>

#include "control/modulation.h"
#include "math/fd_math.h"

/* Current band over which the dead-time correction fades through zero. */
#define DEADTIME_BAND_FRACTION 0.02f

int ctrl_init(ctrl_t *c, const drive_config_t *cfg) {
  *c = (ctrl_t){0};
  c->law = cfg->law;
  c->machine = (pmsm_params_t){cfg->pole_pairs, cfg->rs, cfg->ld, cfg->lq, cfg->lambda_m};
  c->i_max = cfg->i_max;
  c->torque_max = cfg->torque_max;
  c->v_margin = cfg->v_margin;
  c->ts = cfg->ts;
  c->dead_time = cfg->dead_time;
  current_ctrl_cfg_t ccfg = {cfg->rs, cfg->ld, cfg->lq, cfg->lambda_m, cfg->current_bw, cfg->ts};
  current_ctrl_init(&c->foc, &ccfg);

  dfvc_cfg_t dcfg;
  dfvc_cfg_defaults(&dcfg);
  dcfg.rs = cfg->rs;
  dcfg.ls = cfg->ld;
  dcfg.lambda_m = cfg->lambda_m;
  dcfg.pole_pairs = cfg->pole_pairs;
  dcfg.ts = cfg->ts;
  dcfg.omega_c = cfg->flux_obs_wc;
  dcfg.i_max = cfg->i_max;
  dcfg.delta_max = cfg->delta_max;
  dcfg.v_sd_max = cfg->vsd_max;
  dcfg.lambda_min = cfg->flux_min;
  dcfg.lambda_collapse = 0.5f * cfg->flux_min;
  dcfg.v_margin = cfg->v_margin;
  dcfg.pi_bw_flux = cfg->dfvc_flux_bw;
  dcfg.pi_bw_iqs = cfg->dfvc_iqs_bw;
  deadtime_comp_cfg_t tcfg = {cfg->dead_time, cfg->ts, DEADTIME_BAND_FRACTION * cfg->i_max};
  if (dfvc_init(&c->dfvc, &dcfg) != 0 || deadtime_comp_init(&c->dtc, &tcfg) != 0) {
    return -1;
  }
  return 0;
}

void ctrl_reset(ctrl_t *c, drive_law_t law) {
  c->law = law;
  current_ctrl_reset(&c->foc);
  dfvc_reset(&c->dfvc);
  c->v_applied = (ab_t){0.0f, 0.0f};
}

/* Symmetric clamp that lets NaN through, so that a non-finite reference
 * ends in the law's finiteness check (a fault), never at a limit. */
static float clamp_sym_nan(float x, float lim) {
  return x > lim ? lim : (x < -lim ? -lim : x);
}

static void ctrl_step_foc(ctrl_t *c, const ctrl_in_t *in, ctrl_out_t *out) {
  sincos_t sc = frames_sincos(in->theta_e);
  dq_t i = frames_park(in->i_ab, sc);
  dq_t i_ref;
  float t_lim = fd_minf(c->torque_max, pmsm_torque(&c->machine, (dq_t){0.0f, c->i_max}));
  if (in->mode == DRIVE_MODE_CURRENT) {
    i_ref = (dq_t){in->id_ref, in->iq_ref};
  } else {
    float t = clamp_sym_nan(in->torque_ref, t_lim);
    i_ref = (dq_t){0.0f, pmsm_iq_for_torque(&c->machine, t)};
  }
  float mag = sqrtf(i_ref.d * i_ref.d + i_ref.q * i_ref.q);
  if (mag > c->i_max) {
    i_ref.d *= c->i_max / mag;
    i_ref.q *= c->i_max / mag;
  }
  float v_max = c->v_margin * modulation_v_max(in->v_dc);
  dq_t v = current_ctrl_update(&c->foc, i_ref, i, in->omega_e, v_max);
  sincos_t sc_next = frames_sincos(in->theta_e + 1.5f * in->omega_e * c->ts);
  out->v_ref = frames_park_inv(v, sc_next);
  out->i_dq = i;
  /* Expected current over the next period: the reference (the loop tracks
   * it), rotated to the centre of that period. */
  out->i_pred = frames_park_inv(i_ref, sc_next);
  out->torque_min = -t_lim;
  out->torque_max = t_lim;
  out->fault = 0u;
  out->tm = (ctrl_telemetry_t){0};
  out->tm.torque = pmsm_torque(&c->machine, i);
  const float flux_d = c->machine.ld * i.d + c->machine.lambda_m;
  const float flux_q = c->machine.lq * i.q;
  out->tm.flux = sqrtf(flux_d * flux_d + flux_q * flux_q);
}

static void ctrl_step_dfvc(ctrl_t *c, const ctrl_in_t *in, ctrl_out_t *out) {
  dfvc_in_t din = {
      .law = c->law == DRIVE_LAW_DB_DFVC ? DFVC_LAW_DEADBEAT : DFVC_LAW_PI,
      .i_ab = in->i_ab,
      .v_ab_applied = c->v_applied,
      .theta_r = in->theta_e,
      .omega_r = in->omega_e,
      .v_dc = in->v_dc,
      .torque_ref = in->torque_ref,
      .lambda_ref = in->flux_ref,
  };
  dfvc_out_t d;
  dfvc_step(&c->dfvc, &din, &d);
  out->v_ref = d.v_ab_ref;
  out->i_pred = d.i_ab_mid;
  /* rotor-frame currents: from the law's sin/cos of theta_e unless it
   * faulted before computing them */
  out->i_dq = ((d.fault & (DFVC_FAULT_INPUT | DFVC_FAULT_STATE)) != 0u)
                  ? frames_park(in->i_ab, frames_sincos(in->theta_e))
                  : d.i_dq_r;
  out->torque_min = fd_maxf(d.torque_min, -c->torque_max);
  out->torque_max = fd_minf(d.torque_max, c->torque_max);
  out->fault = d.fault;
  out->tm = (ctrl_telemetry_t){.flux = d.lambda_s,
                               .flux_ref = d.lambda_ref,
                               .delta = d.delta,
                               .i_ds = d.i_ds,
                               .i_qs = d.i_qs,
                               .i_qs_ref = d.i_qs_ref,
                               .torque = d.torque};
}

/* Each law writes every field of *out (no zeroing of the whole struct per ISR). */
void ctrl_step(ctrl_t *c, const ctrl_in_t *in, ctrl_out_t *out) {
  switch (c->law) {
  case DRIVE_LAW_FOC:
    ctrl_step_foc(c, in, out);
    break;
  case DRIVE_LAW_PI_DFVC:
  case DRIVE_LAW_DB_DFVC:
    ctrl_step_dfvc(c, in, out);
    break;
  default:
    *out = (ctrl_out_t){0};
    out->fault = 1u;
    break;
  }
  if (!(fd_isfinite(out->v_ref.alpha) && fd_isfinite(out->v_ref.beta))) {
    out->fault = 1u;
  }
}

void ctrl_compensate_deadtime(const ctrl_t *c, const ctrl_out_t *out, float duty[3]) {
  deadtime_comp_apply(&c->dtc, duty, frames_clarke_inv(out->i_pred), duty);
}

void ctrl_set_applied(ctrl_t *c, ab_t v_applied) {
  c->v_applied = v_applied;
}
