/*
 * drive_ctrl.h - the control laws behind one interface: the drive hands
 * them one sample (currents, angle, speed, DC link, references) and gets the
 * alpha-beta voltage for the next period plus telemetry.
 */
#ifndef FLUXDRIVE_DRIVE_CTRL_H
#define FLUXDRIVE_DRIVE_CTRL_H

#include <stdbool.h>
#include <stdint.h>

#include "control/current_ctrl.h"
#include "control/deadtime_comp.h"
#include "control/dfvc.h"
#include "control/speed_ctrl.h"
#include "drive_config.h"
#include "math/frames.h"
#include "model/pmsm.h"

/* Law-specific telemetry (zero where a law has no such quantity). */
typedef struct {
  float flux;     /* stator flux amplitude estimate [Vs] */
  float flux_ref; /* [Vs] */
  float delta;    /* load angle [rad] */
  float i_ds;     /* stator-flux frame currents [A] */
  float i_qs;
  float i_qs_ref;
  float torque; /* torque estimate [N m] */
} ctrl_telemetry_t;

typedef struct {
  ab_t i_ab;     /* measured currents [A] */
  float theta_e; /* electrical angle [rad] */
  float omega_e; /* electrical speed [rad/s] */
  float v_dc;    /* [V] */
  drive_mode_t mode;
  float torque_ref;     /* [N m] */
  float id_ref, iq_ref; /* current mode [A] */
  float flux_ref;       /* 0 = automatic [Vs] */
} ctrl_in_t;

typedef struct {
  ab_t v_ref;                   /* voltage for the next period [V] */
  float torque_min, torque_max; /* torque the law can deliver now [N m] */
  uint32_t fault;               /* non-zero: the law asks for the gates to be disabled */
  dq_t i_dq;                    /* rotor frame currents [A] */
  ab_t i_pred;                  /* currents expected over the next period [A] */
  ctrl_telemetry_t tm;
} ctrl_out_t;

typedef struct {
  drive_law_t law;
  pmsm_params_t machine;
  float i_max, torque_max, v_margin;
  float ts, dead_time;
  current_ctrl_t foc;
  dfvc_t dfvc; /* PI-DFVC and DB-DFVC (Rubino 2020) */
  deadtime_comp_t dtc;
  ab_t v_applied; /* voltage applied over the last period (observers) */
} ctrl_t;

/* Returns 0, or -1 when a law rejects the parameters. */
int ctrl_init(ctrl_t *c, const drive_config_t *cfg);
/* Reset all law states (on enable or law change). */
void ctrl_reset(ctrl_t *c, drive_law_t law);
void ctrl_step(ctrl_t *c, const ctrl_in_t *in, ctrl_out_t *out);
/* Predictive dead-time compensation of the duties (laws that predict the
 * currents over the next period use the prediction, others the present
 * current). */
void ctrl_compensate_deadtime(const ctrl_t *c, const ctrl_out_t *out, float duty[3]);
/* Tell the laws what the modulator actually applied. */
void ctrl_set_applied(ctrl_t *c, ab_t v_applied);

#endif
