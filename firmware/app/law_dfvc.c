/*
 * law_dfvc.c - the DFVC laws of Rubino 2020 for SPM machines behind the law
 * table: PI-DFVC (section IV.7) and DB-DFVC share one state (control/dfvc.h,
 * observer, predictor, references) and differ in the voltage law. They
 * serve isotropic PM machines only: L_s = L_d with L_q within 10 % of it
 * (machine_ls()), and lambda_m > 0 (the load-angle relation (26) and the
 * MTPA flux (22) divide by it); on any other machine the law is
 * unavailable with that reason, and the drive runs the other laws.
 */
#include <stddef.h>

#include "ctrl_laws.h"
#include "math/fd_math.h"

/* Largest relative difference of L_q from L_d an SPM law accepts. */
#define DFVC_ISOTROPY_TOL 0.1f

/* mut: law_check_removed */
FD_COLD static const char *dfvc_check(const ctrl_setup_t *su) {
  const machine_t *m = su->machine;
  if (m->kind != MACHINE_LINEAR) {
    return "DFVC of Rubino 2020 needs a linear machine model";
  }
  if (!(m->lambda_m > 0.0f)) {
    return "DFVC of Rubino 2020 needs a PM machine (lambda_m > 0)";
  }
  if (!machine_is_isotropic(m, DFVC_ISOTROPY_TOL)) {
    return "DFVC of Rubino 2020 needs an isotropic (SPM) machine: |Lq - Ld| > 10 % of Ld";
  }
  if (!(su->cfg->flux_min > 0.0f)) {
    return "DFVC needs flux_min > 0";
  }
  /* mut: dfvc_vsd_max_unchecked */
  if (!(su->cfg->vsd_max > 0.0f)) {
    return "DFVC needs vsd_max > 0 (the limit of its d_s voltage)";
  }
  return NULL;
}

FD_COLD static int dfvc_law_init(ctrl_state_t *s, const ctrl_setup_t *su) {
  const drive_config_t *cfg = su->cfg;
  dfvc_cfg_t d;
  dfvc_cfg_defaults(&d, su->machine);
  d.ts = cfg->ts;
  /* mut: observer_no_crossover */
  d.omega_c = cfg->flux_obs_wc;
  d.i_max = cfg->i_max;
  d.delta_max = cfg->delta_max;
  d.v_sd_max = cfg->vsd_max;
  d.lambda_min = cfg->flux_min;
  d.lambda_collapse = 0.5f * cfg->flux_min;
  d.v_margin = cfg->v_margin;
  /* mut: pi_bw_div4 */
  d.pi_bw_flux = cfg->dfvc_flux_bw;
  d.pi_bw_iqs = cfg->dfvc_iqs_bw;
  /* the output rotation: from theta_s(tau+1) to the centre of the interval
   * the voltage acts, t_out after the sample (dfvc.h, rot_advance) */
  d.rot_advance = fd_clampf(su->t_out / cfg->ts - 1.0f, 0.0f, 1.0f);
  return dfvc_init(&s->dfvc.core, &d);
}

FD_COLD static int pi_init(ctrl_state_t *s, const ctrl_setup_t *su) {
  s->dfvc.law = DFVC_LAW_PI;
  return dfvc_law_init(s, su);
}

FD_COLD static int db_init(ctrl_state_t *s, const ctrl_setup_t *su) {
  s->dfvc.law = DFVC_LAW_DEADBEAT;
  return dfvc_law_init(s, su);
}

static void dfvc_law_reset(ctrl_state_t *s) {
  dfvc_reset(&s->dfvc.core);
}

/* Both rows' step: the voltage law their init chose (ctrl_dfvc_t.law). */
static void dfvc_law_step(ctrl_state_t *s, const ctrl_setup_t *su, const ctrl_in_t *in,
                          ctrl_out_t *out) {
  dfvc_out_t d;
  /* the drive's sample read in place (ctrl_in_t is the core's law_in_t);
   * the telemetry written where the drive publishes it (also on the
   * period it faults: zero then) */
  dfvc_step(&s->dfvc.core, s->dfvc.law, in, &d, out->tm);
  out->v_ref = d.v_ab_ref;
  out->i_pred = d.i_ab_mid;
  /* rotor-frame currents: from the law's sin/cos of theta_e unless it
   * faulted before computing them */
  out->i_dq = ((d.fault & (DFVC_FAULT_INPUT | DFVC_FAULT_STATE)) != 0u)
                  ? frames_park(in->i_ab, frames_sincos(in->theta_e))
                  : d.i_dq_r;
  out->torque_min = fd_maxf(d.torque_min, -su->cfg->torque_max);
  out->torque_max = fd_minf(d.torque_max, su->cfg->torque_max);
  out->fault = d.fault;
}

const ctrl_law_t ctrl_law_pi_dfvc = {"pi_dfvc",      CTRL_CAP_FLUX | CTRL_CAP_DELTA,
                                     dfvc_check,     pi_init,
                                     dfvc_law_reset, dfvc_law_step,
                                     NULL,           0u};
const ctrl_law_t ctrl_law_db_dfvc = {"db_dfvc",      CTRL_CAP_FLUX | CTRL_CAP_DELTA,
                                     dfvc_check,     db_init,
                                     dfvc_law_reset, dfvc_law_step,
                                     NULL,           0u};
