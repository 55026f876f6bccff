/*
 * dfvc_decoupled_pi.h - the regulators of the stator-flux-oriented control of a
 * saturated machine (Varatharajan 2022, section IV): flux amplitude lambda
 * and torque current i_tau, one PI each, behind the transformation T of (23)
 * (decoupled DFVC (27)) or behind a constant gain (constant-gain PI DFVC
 * (26), T = diag(1, 1/b0)).
 *
 * Plant (21): s lambda = u_f, s i_tau = a u_f + b u_tau' with
 *   (u_f, u_tau') = v_ftau - Rs i_ftau - J omega lambda_ftau   (12)
 * so that with u' = T_hat u (23) the loops see s lambda = u_f,
 * s i_tau = u_tau when (a_hat, b_hat) = (a, b).
 *
 * Discrete realisation (choices the paper leaves open, docs/results-varatharajan2022.md):
 *  - Delay: the voltage computed from the samples at tau acts over
 *    [tau+1, tau+2). The loops run on the predictions at tau+1: the
 *    observer's flux lambda(tau+1) (it integrates the voltage applied over
 *    [tau, tau+1)) and i_tau(tau) + Ts u_tau,applied (the virtual input in
 *    force over [tau, tau+1), a Smith predictor in the decoupled
 *    coordinates). The loop is then y(k+1) = y(k) + Ts u(k) exactly.
 *  - Gains (28) in discrete form: the double pole at z = exp(-Omega Ts),
 *      kp = (1 - p^2)/Ts, ki = (1 - p)^2/Ts^2, p = exp(-Omega Ts),
 *    u(k) = kp e(k) + I(k), I(k) = I(k-1) + ki Ts e(k); as Ts -> 0 these
 *    are 2 Omega and Omega^2 of (28). Closed loop of each axis:
 *    y/r = (kp s + ki)/(s + Omega)^2 in the limit.
 *  - Voltage limit: |v_f| <= min(v_f_max, v_max), then |v_tau| <=
 *    sqrt(v_max^2 - v_f^2) (the flux axis first, as the SPM laws);
 *    anti-windup by conditional integration (an axis whose output is
 *    limited does not integrate an error that pushes further into the
 *    limit), and the predictor uses the virtual input actually applied, so
 *    the loops leave the limit without overshoot from a stale prediction.
 */
#ifndef FD_CONTROL_DFVC_DECOUPLED_PI_H
#define FD_CONTROL_DFVC_DECOUPLED_PI_H

#include "math/frames.h"
#include "model/sfo_model.h"

typedef struct {
  float ts;      /* [s] */
  float omega;   /* design bandwidth Omega [rad/s], (28) */
  float v_f_max; /* flux-axis voltage limit [V] */
} dfvc_decoupled_pi_cfg_t;

typedef struct {
  dfvc_decoupled_pi_cfg_t cfg;
  float kp, ki;   /* discrete (28) [1/s], [1/s^2] */
  float kits;     /* ki Ts, the integrators' gain per period [1/s] */
  float integ_f;  /* integral part of u_f [V] */
  float integ_t;  /* integral part of u_tau [A/s] */
  float u_t_prev; /* u_tau applied over [tau, tau+1) [A/s] */
} dfvc_decoupled_pi_t;

typedef struct {
  float lambda_ref;  /* [Vs] */
  float itau_ref;    /* [A] */
  float lambda_next; /* observer's flux amplitude at tau+1 [Vs] */
  dq_t i_ft;         /* current in the stator-flux frame at tau [A] */
  float omega_r;     /* electrical rotor speed [rad/s] */
  float rs;          /* [Ohm] */
  sfo_gains_t g;     /* gains of the transformation (b > 0) */
  float v_max;       /* voltage amplitude available [V] */
} dfvc_decoupled_pi_in_t;

enum { DFVC_DECOUPLED_PI_SAT_F = 1u << 0, DFVC_DECOUPLED_PI_SAT_T = 1u << 1 };

typedef struct {
  dq_t v_ft;    /* (f, tau) voltage [V] */
  dq_t u;       /* virtual inputs applied (u_f [V], u_tau [A/s]) */
  unsigned sat; /* DFVC_DECOUPLED_PI_SAT_* */
} dfvc_decoupled_pi_out_t;

/* Returns 0, or -1 for invalid parameters (ts, omega, v_f_max > 0 finite). */
int dfvc_decoupled_pi_init(dfvc_decoupled_pi_t *c, const dfvc_decoupled_pi_cfg_t *cfg);
void dfvc_decoupled_pi_reset(dfvc_decoupled_pi_t *c);
void dfvc_decoupled_pi_step(dfvc_decoupled_pi_t *c, const dfvc_decoupled_pi_in_t *in,
                            dfvc_decoupled_pi_out_t *out);

#endif
