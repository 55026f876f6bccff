/*
 * law_foc.c - FOC: rotor-frame PI current control with decoupling, the
 * papers' baseline (control/current_ctrl.h). Torque mode follows the MTPA
 * trajectory of the machine model (model/machine.h: i_d = 0 on an SPM
 * machine, i_d < 0 on interior-PM and reluctance machines). The voltage
 * computed from the samples acts over the next period: the inverse Park
 * uses the angle extrapolated to the centre of that interval (t_out after
 * the current sample, from the HAL's timestamps).
 */
#include <math.h>
#include <stddef.h>

#include "ctrl_laws.h"
#include "math/fd_math.h"

/* Symmetric clamp that lets NaN through, so that a non-finite reference
 * ends in the finiteness check (a fault), never at a limit. */
static float clamp_sym_nan(float x, float lim) {
  return x > lim ? lim : (x < -lim ? -lim : x);
}

FD_COLD static const char *foc_check(const ctrl_setup_t *su) {
  (void)su;
  return NULL; /* any machine: current mode always, torque mode on its MTPA */
}

FD_COLD static int foc_init(ctrl_state_t *s, const ctrl_setup_t *su) {
  const current_ctrl_cfg_t ccfg = {su->machine, su->cfg->current_bw, su->cfg->ts};
  current_ctrl_init(&s->foc.cc, &ccfg);
  s->foc.t_mtpa_max = machine_mtpa_torque(su->machine, su->cfg->i_max);
  s->foc.mtpa_t = NAN;
  return 0;
}

/* The MTPA cache primed with the answer for no torque, the least current
 * (none) on every machine: the run's first period starts from zero torque
 * (the speed loop's), and solving it there met the speed loop's first
 * period in one ISR (issue 24 point 8: the sensorless worst case). */
static void foc_reset(ctrl_state_t *s) {
  current_ctrl_reset(&s->foc.cc);
  s->foc.mtpa_t = 0.0f;
  s->foc.mtpa_i = (dq_t){0.0f, 0.0f};
}

/* machine_mtpa_current(m, t), computed again only when t changes. */
static dq_t foc_mtpa(ctrl_foc_t *f, const machine_t *m, float t) {
  /* a NaN on either side compares false: solved again (a NaN reference faults) */
  if (!(fabsf(t - f->mtpa_t) <= 0.0f)) {
    f->mtpa_i = machine_mtpa_current(m, t);
    f->mtpa_t = t;
  }
  return f->mtpa_i;
}

static void foc_step(ctrl_state_t *s, const ctrl_setup_t *su, const ctrl_in_t *in,
                     ctrl_out_t *out) {
  const machine_t *m = su->machine;
  const float i_max = su->cfg->i_max;
  const sincos_t sc = frames_sincos(in->theta_e);
  const dq_t i = frames_park(in->i_ab, sc);
  out->i_dq = i;
  const float t_lim = fd_minf(su->cfg->torque_max, s->foc.t_mtpa_max);
  dq_t i_ref;
  if (in->current) {
    i_ref = (dq_t){in->id_ref, in->iq_ref};
  } else {
    i_ref = foc_mtpa(&s->foc, m, clamp_sym_nan(in->torque_ref, t_lim));
  }
  const float mag = sqrtf(i_ref.d * i_ref.d + i_ref.q * i_ref.q);
  if (mag > i_max) {
    i_ref.d *= i_max / mag;
    i_ref.q *= i_max / mag;
  }
  /* one model evaluation for the torque, the telemetry and the loop's
   * feed-forward; what only reports is done before the calls below, so
   * that the fewest values live across them */
  const dq_t flux = machine_flux(m, i);
  const float t_now = 1.5f * m->pole_pairs * (flux.d * i.q - flux.q * i.d);
  /* every field written (no zero-fill call in the ISR): FOC has no flux
   * loop, load angle or observer */
  ctrl_telemetry_t *tm = out->tm; /* where the drive publishes it */
  tm->flux = sqrtf(flux.d * flux.d + flux.q * flux.q);
  tm->flux_ref = 0.0f;
  tm->delta = 0.0f;
  tm->lam_d = 0.0f;
  tm->lam_q = 0.0f;
  tm->delta_lazy = false;
  tm->i_ds = 0.0f;
  tm->i_qs = 0.0f;
  tm->i_qs_ref = 0.0f;
  tm->torque = t_now;
  tm->obs_err = 0.0f;
  /* The voltage acts over the next period: the angle at its centre. The
   * current expected over it is the reference (the loop tracks it), rotated
   * there. */
  const sincos_t sc_next = frames_sincos(in->theta_e + in->omega_e * su->t_out);
  out->i_pred = frames_park_inv(i_ref, sc_next);
  const float v_max = su->cfg->v_margin * in->v_lin;
  const dq_t v = current_ctrl_step(&s->foc.cc, i_ref, i, flux, in->omega_e, v_max);
  out->v_ref = frames_park_inv(v, sc_next);
  out->fault = 0u;
  /* The torque deliverable now. On the voltage limit (the current loop's
   * output on the circle v_margin v_lin: a DC-link sag, a speed beyond what
   * the voltage allows) the present current's torque is all the voltage
   * gives in the reference's direction, between zero and t_lim; a torque
   * against the reference, or beyond it, stays a loss of control
   * (drive_monitor). The speed loop's anti-windup takes the same bound. */
  out->torque_min = -t_lim;
  out->torque_max = t_lim;
  /* mut: foc_voltage_limit_torque_ignored */
  if (s->foc.cc.limited != 0) {
    if (in->torque_ref > 0.0f) {
      /* mut: foc_voltage_limit_no_zero_bound */
      out->torque_max = fd_clampf(t_now, 0.0f, t_lim);
    } else if (in->torque_ref < 0.0f) {
      out->torque_min = fd_clampf(t_now, -t_lim, 0.0f);
    }
  }
}

const ctrl_law_t ctrl_law_foc = {"foc",     CTRL_CAP_CURRENT, foc_check, foc_init,
                                 foc_reset, foc_step,         NULL,      0u};
