/*
 * flux_observer.h - hybrid stator-flux observer of an SPM machine in the
 * stationary frame with one-step flux prediction (Rubino 2020, Fig. 3,
 * eqs. (2), (19), (20)).
 *
 * Discrete realisation of Fig. 3 (backward-Euler integrator, output taken
 * before the integrator's delay):
 *   lambda_cm(t)   = Ls i(t) + lambda_m e^{j theta_r(t)}             eq. (2)
 *   e(t)           = v(t) - Rs (i(t) + i(t+1))/2 + omega_c (lambda_cm(t) - lambda_hat(t))
 *   lambda_hat(t+1) = lambda_hat(t) + Ts e(t)                        eq. (19)
 * with v(t) the voltage applied over [t, t+1) and i(t+1) the MPE prediction
 * (eq. (21)). The paper writes Rs i(t); the mean over the period removes the
 * bias Rs |i| w Ts / 2 of the held drop (flux error 0.1 % at 100 rpm, 1.5 %
 * at 1200 rpm on the Table I machine). Passing i_next = i gives the paper's
 * form. In the z domain
 *   lambda_hat = H(z) lambda_cm + (1 - H(z)) (back-EMF integral),
 *   H(z) = omega_c Ts / (z - 1 + omega_c Ts),
 * the discrete form of eq. (20): the current model below omega_c, the
 * back-EMF integration above it.
 *
 * Derived outputs: amplitude and angle theta_s of lambda_hat at t and t+1,
 * flux-frame speed omega_s (first-order low-pass, bandwidth omega_s_bw, on
 * the wrapped difference of theta_s), load angle delta = theta_s - theta_r,
 * the current in the stator-flux frame (i_ds, i_qs) and the torque
 * 3/2 p lambda_s i_qs (eq. (16)).
 *
 * The first update after init/reset starts from the current model
 * (lambda_hat = lambda_cm), omega_s from omega_r.
 */
#ifndef FD_ESTIMATION_FLUX_OBSERVER_H
#define FD_ESTIMATION_FLUX_OBSERVER_H

#include "math/frames.h"
#include "model/machine.h"

typedef struct {
  const machine_t *machine; /* SPM: Rs, Ls = machine_ls(), lambda_m, p */
  float ts;                 /* [s] */
  float omega_c;            /* crossover (observer gain) [rad/s]; paper: 125 */
  float omega_s_bw;         /* low-pass bandwidth of the omega_s derivative [rad/s] */
} flux_observer_cfg_t;

typedef struct {
  flux_observer_cfg_t cfg;
  float alpha_s;   /* 1 - exp(-omega_s_bw Ts) */
  ab_t lambda_hat; /* estimate at the next update's sample [Vs] */
  float theta_s_prev;
  float omega_s;      /* filtered flux-frame speed [rad/s] */
  int started;        /* 0 until the first update */
  int angles_started; /* 0 until the first flux_observer_angles() */
} flux_observer_t;

typedef struct {
  ab_t lambda;         /* lambda_hat at t [Vs] */
  float lambda_s;      /* |lambda_hat| at t [Vs] */
  float theta_s;       /* angle of lambda_hat at t [rad], (-pi, pi] */
  sincos_t sc_s;       /* sin, cos of theta_s */
  ab_t lambda_cm;      /* current model at t, eq. (2) [Vs] */
  ab_t lambda_next;    /* prediction at t+1, eq. (19) [Vs] */
  float lambda_s_next; /* [Vs] */
  /* its angle is left to the caller (fd_atan2f(sc_s_next.s, sc_s_next.c)):
   * the DFVC needs it on a rare branch only, so no atan2 every period */
  sincos_t sc_s_next;
  float omega_s; /* filtered d theta_s / dt [rad/s] */
  float delta;   /* load angle theta_s - theta_r at t, wrapped [rad] */
  dq_t i_dqs;    /* current in the stator-flux frame at t [A] */
  float torque;  /* 3/2 p lambda_s i_qs [N m] */
} flux_observer_out_t;

/* Returns 0, or -1 for invalid parameters (no machine, ts > 0, omega_c >= 0,
 * omega_s_bw > 0, all finite). */
int flux_observer_init(flux_observer_t *o, const flux_observer_cfg_t *cfg);
void flux_observer_reset(flux_observer_t *o);
/* i: measured current at t [A]; i_next: predicted current at t+1 [A];
 * v: voltage applied over [t, t+1) [V]; theta_r, omega_r: electrical rotor
 * angle [rad] and speed [rad/s] at t. */
void flux_observer_update(flux_observer_t *o, ab_t i, ab_t i_next, ab_t v, float theta_r,
                          float omega_r, flux_observer_out_t *out);
/* The same with sc_r = (sin, cos) of theta_r given by the caller. */
void flux_observer_update_sc(flux_observer_t *o, ab_t i, ab_t i_next, ab_t v, float theta_r,
                             sincos_t sc_r, float omega_r, flux_observer_out_t *out);
/* The estimate with the current model lambda_cm = Lambda(i) in (alpha,
 * beta) given by the caller: eq. (24) of Varatharajan 2022, s lambda_hat =
 * v - Rs i + e^{J theta} G (lambda^i_dq - lambda_hat_dq) with G = g I, is
 * this observer with omega_c = g and the flux map (or any machine model) as
 * the current model (the rotation e^{J theta} of a diagonal G commutes with
 * the difference). The SPM model of update_sc is one such current model.
 * Fills every field but the angles (theta_s, omega_s, delta: 0), which
 * cost an atan2 a period: flux_observer_angles(). */
void flux_observer_update_cm(flux_observer_t *o, ab_t i, ab_t i_next, ab_t v, ab_t lambda_cm,
                             flux_observer_out_t *out);
/* The angles of out (after update_cm): theta_s, the filtered
 * omega_s and the load angle delta = theta_s - theta_r. */
void flux_observer_angles(flux_observer_t *o, float theta_r, float omega_r,
                          flux_observer_out_t *out);

#endif
