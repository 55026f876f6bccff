/*
 * current_predictor.h - model predictive current estimator (MPE) of an SPM
 * machine in the stationary (alpha, beta) frame (Rubino 2020, Fig. 4 and
 * eq. (21)): one-step prediction of the stator current from the current at
 * tau, the voltage applied over [tau, tau+1), the rotor speed and the PM
 * flux vector lambda_m e^{j theta_r}.
 *
 * Two forms (cfg.mode):
 *  - CURRENT_PREDICTOR_EQ21: eq. (21) as printed,
 *      i(t+1) = k_s i(t) + (1 - k_s)/Rs (v(t) - j omega_r lambda_m e^{j theta_r(t)}),
 *    the back-EMF held at its value at tau over the period. Its error grows
 *    with omega_r Ts (0.045 A at 1200 rpm on the Table I machine).
 *  - CURRENT_PREDICTOR_EXACT (default): same structure, but the back-EMF
 *    term is discretised where it is constant, in the rotor frame, with
 *    eqs. (10)-(15) at omega_xy = omega_r and rotated back to (alpha, beta) at
 *    theta_r + omega_r Ts; the voltage term stays as in (21) (the modulator
 *    holds v constant in alpha-beta). By superposition this is the exact
 *    solution of the continuous model for constant speed over the period.
 */
#ifndef FD_ESTIMATION_CURRENT_PREDICTOR_H
#define FD_ESTIMATION_CURRENT_PREDICTOR_H

#include "math/frames.h"
#include "model/machine.h"
#include "model/spm_discrete.h"

typedef enum {
  CURRENT_PREDICTOR_EXACT = 0, /* back-EMF exact for constant speed (default) */
  CURRENT_PREDICTOR_EQ21 = 1   /* eq. (21) literally: back-EMF held at tau */
} current_predictor_mode_t;

typedef struct {
  const machine_t *machine; /* SPM: Rs, Ls = machine_ls(), lambda_m */
  float ts;                 /* [s] */
  current_predictor_mode_t mode;
} current_predictor_cfg_t;

typedef struct {
  current_predictor_cfg_t cfg;
  spm_discrete_t disc; /* k_s, (1 - k_s)/Rs computed once */
} current_predictor_t;

/* Returns 0, or -1 for invalid parameters (no machine, ts <= 0). */
int current_predictor_init(current_predictor_t *p, const current_predictor_cfg_t *cfg);
/* No dynamic state: recomputes the discretisation constants from cfg. */
void current_predictor_reset(current_predictor_t *p);
/* i: current at tau [A]; v: voltage applied over [tau, tau+1) [V];
 * theta_r, omega_r: electrical rotor angle at tau [rad] and speed [rad/s].
 * Returns the predicted current at tau+1. Rubino 2020, eq. (21). */
ab_t current_predictor_step(const current_predictor_t *p, ab_t i, ab_t v, float theta_r,
                            float omega_r);

/* What the predictions at one rotor speed share, computed once per ISR:
 * the coefficients (12)-(15) at omega_r and the rotation over a period. */
typedef struct {
  float omega_r;            /* [rad/s] */
  spm_discrete_coef_t coef; /* eqs. (14)-(15) at omega_xy = omega_r */
  sincos_t rot;             /* e^{j omega_r Ts} */
  sincos_t half;            /* e^{j omega_r Ts / 2}: fd_sincosf(0.5f * (omega_r * Ts)) */
} current_predictor_speed_t;

void current_predictor_speed(const current_predictor_t *p, float omega_r,
                             current_predictor_speed_t *w);
/* current_predictor_step() at the speed of w, with the rotor angle at t
 * given by its sin and cos sc_r (no sin/cos evaluated). */
ab_t current_predictor_step_sc(const current_predictor_t *p, const current_predictor_speed_t *w,
                               ab_t i, ab_t v, sincos_t sc_r);

#endif
