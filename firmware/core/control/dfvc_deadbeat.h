/*
 * dfvc_deadbeat.h - deadbeat flux and torque-current laws of the DB-DFVC
 * (Rubino 2020, eqs. (27)-(33)), in the stator-flux frame (ds, qs).
 *
 * One-step delay compensation, eq. (28): the voltage computed at tau is
 * applied over [tau+1, tau+2); it is chosen so that lambda_s and i_qs reach
 * their references at tau+2, starting from the predicted values at tau+1
 * (MPE eq. (21) and flux prediction (19)):
 *   v_ds* = Rs i_ds(t+1) + (lambda* - lambda_s(t+1)) / Ts                 (29)
 *   v_qs* = Rs i_qs(t+1) + w_delta(t+1) Ls i_ds(t+1) + w_r lambda_s(t+1)
 *           + Ls/Ts (i_qs* - i_qs(t+1))                                     (33)
 * Limits: |v_ds| <= min(v_sd_max, v_max) (paper: v_sd,max), then the q_s
 * axis gets what is left of the circle, |v_qs| <= sqrt(v_max^2 - v_ds^2)
 * (flux priority; the paper's min-max PWM saturates the duties, this keeps
 * the saturated vector inside the linear range with the flux axis served
 * first, which is what keeps the flux regulated in transients).
 *
 * omega_delta over [tau+1, tau+2) (the paper writes w~_delta^{tau+1} and
 * leaves its computation open). Two estimates are offered to the caller:
 *  - dfvc_deadbeat_omega_delta_target(): (delta* - delta(t+1)) / Ts with
 *    sin(delta*) = sin(delta(t+1)) + Ls (i_qs* - i_qs(t+1)) / lambda_m, the
 *    load angle at which an SPM machine carries i_qs* (q_s row of (16), the
 *    relation behind (26)), taken as an increment from the predicted state
 *    so that detuned Ls, lambda_m scale the step instead of biasing v_qs.
 *    It predicts the load-angle step that the commanded i_qs step causes
 *    in the very interval the voltage acts (default in dfvc.h).
 *  - the observed rate (delta(t+1) - delta(t)) / Ts (one interval late).
 */
#ifndef FD_CONTROL_DFVC_DEADBEAT_H
#define FD_CONTROL_DFVC_DEADBEAT_H

#include "math/frames.h"
#include "model/machine.h"

typedef struct {
  const machine_t *machine; /* SPM: Rs, Ls = machine_ls(), lambda_m > 0 */
  float ts;                 /* [s] */
  float v_sd_max;           /* d_s voltage limit [V]; paper: 60 V */
} dfvc_deadbeat_cfg_t;

typedef struct {
  dfvc_deadbeat_cfg_t cfg;
  float inv_ts; /* 1/Ts */
  float ls_ts;  /* Ls/Ts */
} dfvc_deadbeat_t;

typedef struct {
  float lambda_ref;    /* lambda* [Vs] */
  float iqs_ref;       /* i_qs* [A] */
  float lambda_s_next; /* predicted flux amplitude at tau+1 [Vs] */
  dq_t i_dqs_next;     /* predicted current at tau+1 in the flux frame at tau+1 [A] */
  float omega_r;       /* electrical rotor speed at tau+1 [rad/s] */
  float omega_delta;   /* load-angle rate over [tau+1, tau+2) [rad/s] */
  float v_max;         /* available voltage amplitude [V] */
} dfvc_deadbeat_in_t;

enum {
  DFVC_DEADBEAT_SAT_D = 1u << 0, /* v_ds was limited */
  DFVC_DEADBEAT_SAT_Q = 1u << 1  /* v_qs was limited */
};

typedef struct {
  dq_t v_dqs;     /* limited (ds, qs) voltage reference [V] */
  dq_t v_dqs_raw; /* before the limits [V] */
  unsigned sat;   /* DFVC_DEADBEAT_SAT_* */
} dfvc_deadbeat_out_t;

/* Returns 0, or -1 for invalid parameters. */
int dfvc_deadbeat_init(dfvc_deadbeat_t *db, const dfvc_deadbeat_cfg_t *cfg);
/* No dynamic state: recomputes the derived constants. */
void dfvc_deadbeat_reset(dfvc_deadbeat_t *db);
/* (delta* - delta_next)/Ts, delta* = asin(Ls i_qs* / lambda_m) [rad/s]. */
float dfvc_deadbeat_omega_delta_target(const dfvc_deadbeat_t *db, float iqs_ref, float iqs_next,
                                       float delta_next);
/* The same with sc_delta = (sin, cos) of delta_next given by the caller. */
float dfvc_deadbeat_omega_delta_target_sc(const dfvc_deadbeat_t *db, float iqs_ref, float iqs_next,
                                          float delta_next, sincos_t sc_delta);
/* Eqs. (29) and (33) with the limits. */
void dfvc_deadbeat_step(const dfvc_deadbeat_t *db, const dfvc_deadbeat_in_t *in,
                        dfvc_deadbeat_out_t *out);

#endif
