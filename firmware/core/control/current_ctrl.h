/*
 * current_ctrl.h - rotor-frame (dq) current regulator: the FOC baseline the
 * papers compare against. Two PI regulators designed by pole-zero
 * cancellation (kp = wc*L, ki = wc*Rs, closed loop ~ wc/(s+wc)), decoupling
 * feed-forward (-we*Lq*iq on d; +we*(Ld*id + lambda_m) on q), and a circular
 * voltage limit with d-axis priority; the integrators stop when limited.
 * On a flux-map machine kp follows the incremental inductance at the
 * reference (current_ctrl.c).
 */
#ifndef FD_CONTROL_CURRENT_CTRL_H
#define FD_CONTROL_CURRENT_CTRL_H

#include "math/frames.h"
#include "math/pi_ctrl.h"
#include "model/machine.h"

typedef struct {
  const machine_t *machine; /* Rs, Ld, Lq, lambda_m (linear) */
  float bandwidth;          /* closed-loop bandwidth wc [rad/s] */
  float ts;                 /* sampling period [s] */
} current_ctrl_cfg_t;

typedef struct {
  current_ctrl_cfg_t cfg;
  pi_ctrl_t pi_d;
  pi_ctrl_t pi_q;
  int limited; /* 1 when the last output was on the voltage limit */
} current_ctrl_t;

void current_ctrl_init(current_ctrl_t *cc, const current_ctrl_cfg_t *cfg);
void current_ctrl_reset(current_ctrl_t *cc);
/* i_ref, i: dq currents [A]; we: electrical speed [rad/s]; v_max: available
 * voltage amplitude [V]. Returns the dq voltage reference, |v| <= v_max. */
dq_t current_ctrl_update(current_ctrl_t *cc, dq_t i_ref, dq_t i, float we, float v_max);
/* current_ctrl_update with the flux linkage at the measured current,
 * flux_i = machine_flux(machine, i), given by a caller that needs it too
 * (law_foc's torque estimate: one model evaluation per period, not two). */
dq_t current_ctrl_step(current_ctrl_t *cc, dq_t i_ref, dq_t i, dq_t flux_i, float we, float v_max);

#endif
