/*
 * law_dfvc_decoupled.c - the decoupled DFVC of Varatharajan 2022 behind the law
 * table (control/dfvc_decoupled.h): any machine model (flux map or linear); gain
 * set (dfvc_decoupled_gains: 0 proposed (a, b) (22), 1 state of the art (a', b')
 * (17), 2 constant-gain PI (26)) and references (dfvc_decoupled_refs: 0 the map's
 * tables (29)-(31), 1 online (32), (34)) from the parameter table. The
 * current-model error factors cm_scale_d, cm_scale_q are LIVE (read every
 * period); the other parameters re-initialise the law.
 */
#include <stddef.h>

#include "ctrl_laws.h"
#include "math/fd_math.h"

FD_COLD static const char *dfvc_decoupled_check(const ctrl_setup_t *su) {
  const drive_config_t *cfg = su->cfg;
  if (!(cfg->flux_min > 0.0f)) {
    return "decoupled DFVC needs flux_min > 0";
  }
  if (cfg->dfvc_decoupled_refs == (uint16_t)DFVC_DECOUPLED_REFS_LUT &&
      su->machine->kind != MACHINE_FLUX_MAP) {
    return "decoupled DFVC with LUT references (dfvc_decoupled_refs 0) needs a flux map";
  }
  if (!(cfg->flux_min <= dfvc_decoupled_flux_cap(su->machine, cfg->i_max))) {
    return "decoupled DFVC needs flux_min at most the largest stator flux the machine reaches "
           "at i_max";
  }
  return NULL;
}

FD_COLD static int dfvc_decoupled_law_init(ctrl_state_t *s, const ctrl_setup_t *su) {
  const drive_config_t *cfg = su->cfg;
  dfvc_decoupled_cfg_t d;
  dfvc_decoupled_cfg_defaults(&d, su->machine);
  d.ts = cfg->ts;
  d.g = cfg->sat_obs_g;
  d.omega = cfg->dfvc_decoupled_bw;
  /* v_f_max stays at its default: the voltage circle alone (vsd_max is the
   * SPM laws' d_s limit) */
  d.rot_advance = fd_clampf(su->t_out / cfg->ts - 1.0f, 0.0f, 1.0f);
  d.gains = (dfvc_decoupled_gains_t)cfg->dfvc_decoupled_gains;
  d.refs_mode = (dfvc_decoupled_refs_mode_t)cfg->dfvc_decoupled_refs;
  d.i_max = cfg->i_max;
  d.lambda_min = cfg->flux_min;
  d.k_v = cfg->k_v;
  d.k_t = cfg->k_t;
  d.k_a = cfg->k_a;
  return dfvc_decoupled_init(&s->dfvc_decoupled, &d);
}

static void dfvc_decoupled_law_reset(ctrl_state_t *s) {
  dfvc_decoupled_reset(&s->dfvc_decoupled);
}

static void dfvc_decoupled_law_step(ctrl_state_t *s, const ctrl_setup_t *su, const ctrl_in_t *in,
                                    ctrl_out_t *out) {
  const dfvc_decoupled_in_t din = {
      .i_ab = in->i_ab,
      .v_ab_applied = in->v_applied,
      .theta_r = in->theta_e,
      .omega_r = in->omega_e,
      .v_lin = in->v_lin,
      .torque_ref = in->torque_ref,
      .lambda_ref = in->flux_ref,
      .cm_scale = {su->cfg->cm_scale_d, su->cfg->cm_scale_q},
  };
  dfvc_decoupled_out_t d;
  dfvc_decoupled_step(&s->dfvc_decoupled, &din, &d);
  out->v_ref = d.v_ab_ref;
  out->i_pred = d.i_ab_mid;
  out->i_dq = (d.fault != 0u) ? frames_park(in->i_ab, frames_sincos(in->theta_e)) : d.i_dq;
  out->torque_max = fd_minf(d.r.torque_max, su->cfg->torque_max);
  out->torque_min = -out->torque_max;
  out->fault = d.fault;
  /* every field written (no zero-fill call in the ISR) */
  ctrl_telemetry_t *tm = out->tm; /* where the drive publishes it */
  tm->flux = d.lambda_s;
  tm->flux_ref = d.r.lambda_ref;
  tm->delta = 0.0f; /* telemetry only: its readers take it from lam_d, lam_q */
  tm->lam_d = d.lambda_dq.d;
  tm->lam_q = d.lambda_dq.q;
  tm->delta_lazy = true;
  tm->i_ds = d.i_ft.d;
  tm->i_qs = d.i_ft.q;
  tm->i_qs_ref = d.r.itau_ref;
  tm->torque = d.torque;
  tm->obs_err = d.obs_err;
}

/* Its signals (signal_row.h): what the last step found, dfvc_decoupled_tm_t. */
#define SAT_SIG(field)                                                                             \
  FD_COLD static double sig_##field(const void *owner) {                                           \
    return (double)((const ctrl_state_t *)owner)->dfvc_decoupled.tm.field;                         \
  }
SAT_SIG(flux_mtpa)
SAT_SIG(torque_mtpv)
SAT_SIG(gain_a)
SAT_SIG(gain_b)
SAT_SIG(mtpv_angle)
#undef SAT_SIG
FD_COLD static double sig_mtpa_angle(const void *owner) {
  return (double)dfvc_decoupled_tm_mtpa_angle(&((const ctrl_state_t *)owner)->dfvc_decoupled.tm);
}

static const signal_row_t sat_signals[] = {
    {"flux_mtpa", SIGNAL_F32, "Vs", "MTPA flux, table (29) or adapted online (32)", sig_flux_mtpa},
    {"torque_mtpv", SIGNAL_F32, "N m", "MTPV torque limit, (31) or (34), margin k_T included",
     sig_torque_mtpv},
    {"gain_a", SIGNAL_F32, "1/H", "a_hat of the transformation (23) in use", sig_gain_a},
    {"gain_b", SIGNAL_F32, "1/H", "b_hat of the transformation (23) in use", sig_gain_b},
    {"mtpa_angle", SIGNAL_F32, "1",
     "sine of the phase of lambda^a from i, on the line (0 on MTPA, (7))", sig_mtpa_angle},
    {"mtpv_angle", SIGNAL_F32, "rad",
     "phase of i^a from lambda, on the line (0 on MTPV, (10)); 0 with LUT references (not "
     "computed)",
     sig_mtpv_angle},
};

const ctrl_law_t ctrl_law_dfvc_decoupled = {"dfvc_decoupled",
                                            CTRL_CAP_FLUX,
                                            dfvc_decoupled_check,
                                            dfvc_decoupled_law_init,
                                            dfvc_decoupled_law_reset,
                                            dfvc_decoupled_law_step,
                                            sat_signals,
                                            sizeof sat_signals / sizeof sat_signals[0]};
