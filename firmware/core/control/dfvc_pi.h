/*
 * dfvc_pi.h - PI-DFVC baseline (Rubino 2020, section IV.7; structure of
 * Pellegrino et al. 2011, ref. [12]) in the stator-flux frame, with the
 * same references as the deadbeat law and no prediction: the regulators act
 * on the observed flux and measured current at tau.
 *
 * Plant (Rubino 2020, eqs. (16), (32)):
 *   d lambda_s/dt = v_ds - Rs i_ds
 *   Ls d i_qs/dt  = v_qs - Rs i_qs - w_r lambda_s - w_delta Ls i_ds
 * Feed-forward (the paper's "calibrated feed-forward voltage terms"; our
 * reading: the disturbance terms f of (27), so that the PIs only supply the
 * derivative of the controlled variable):
 *   ff_d = Rs i_ds,   ff_q = w_r lambda_s + w_delta Ls i_ds   (values at tau)
 * Gains from the bandwidths (rad/s):
 *   flux:  plant 1/s after ff_d.  kp = w_f, ki = w_f^2 / 4 (integral zero
 *          at w_f/4, as the speed loop's, to absorb Rs and ff errors);
 *          closed loop ~ w_f/(s + w_f). With the zero a decade below, the
 *          flux error after a torque step decayed with 1/(0.1 w_f) = 1.6 ms
 *          and the torque stayed outside 5 % of a 1 N m step for 16
 *          samples (18 around the reference); at w_f/4: 14 and 14 (the
 *          paper's PI-DFVC: eleven, Fig. 22).
 *   i_qs:  plant 1/(Ls s + Rs).    kp = w_i Ls, ki = w_i Rs (pole-zero
 *          cancellation); closed loop ~ w_i/(s + w_i).
 * The paper uses 1 kHz for both (w = 2 pi 1000 rad/s); with the 1.5 Ts
 * loop delay at 16 kHz the phase margin is 56 deg.
 * Limits as the deadbeat law: |v_ds| <= min(v_sd_max, v_max), then
 * |v_qs| <= sqrt(v_max^2 - v_ds^2).
 * Anti-windup by tracking: while the output is limited and the error pushes
 * further into the limit, the integral is set to its steady-state value at
 * the present current (Rs i_qs for the i_qs loop, 0 for the flux loop whose
 * ff_d carries Rs i_ds) instead of integrating; it is also bounded by the
 * output range minus the feed-forward. So the loop leaves saturation with
 * the right integral and the linear response stays first order. (Freezing
 * the integral instead keeps the pre-transient Rs i_qs: after a -20 -> 20 N m
 * reversal that is a 33 V error removed with the slow zero Rs/Ls.)
 * math/pi_ctrl is not used on purpose: its back-calculation re-aligns the
 * integral to (limit - kp e - ff), and in a large transient (torque
 * reversal: kp e ~ 1.7 kV on the i_qs loop) that parks the integral near
 * -1.5 kV, leaving a slow tail ~1/(ki/kp) = Ls/Rs after the saturation.
 */
#ifndef FD_CONTROL_DFVC_PI_H
#define FD_CONTROL_DFVC_PI_H

#include "math/frames.h"
#include "model/machine.h"

typedef struct {
  const machine_t *machine; /* SPM: Rs, Ls = machine_ls() */
  float ts;                 /* [s] */
  float bw_flux;            /* flux loop bandwidth [rad/s] */
  float bw_iqs;             /* i_qs loop bandwidth [rad/s] */
  float v_sd_max;           /* d_s voltage limit [V] */
} dfvc_pi_cfg_t;

typedef struct {
  dfvc_pi_cfg_t cfg;
  float kp_flux, ki_flux; /* [V/Vs], [V/(Vs s)] */
  float kp_iqs, ki_iqs;   /* [V/A], [V/(A s)] */
  float integ_d;          /* integral part of v_ds [V] */
  float integ_q;          /* integral part of v_qs [V] */
} dfvc_pi_t;

typedef struct {
  float lambda_ref;  /* [Vs] */
  float iqs_ref;     /* [A] */
  float lambda_s;    /* observed amplitude at tau [Vs] */
  dq_t i_dqs;        /* measured current in the flux frame at tau [A] */
  float omega_r;     /* [rad/s] */
  float omega_delta; /* filtered load-angle rate omega_s - omega_r [rad/s] */
  float v_max;       /* available voltage amplitude [V] */
} dfvc_pi_in_t;

typedef struct {
  dq_t v_dqs;   /* [V] */
  unsigned sat; /* DFVC_PI_SAT_* */
} dfvc_pi_out_t;

enum { DFVC_PI_SAT_D = 1u << 0, DFVC_PI_SAT_Q = 1u << 1 };

/* Returns 0, or -1 for invalid parameters. */
int dfvc_pi_init(dfvc_pi_t *c, const dfvc_pi_cfg_t *cfg);
/* Clears both integrals (bumpless thanks to the feed-forwards). */
void dfvc_pi_reset(dfvc_pi_t *c);
void dfvc_pi_step(dfvc_pi_t *c, const dfvc_pi_in_t *in, dfvc_pi_out_t *out);

#endif
