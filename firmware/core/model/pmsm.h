/*
 * pmsm.h - linear PM synchronous machine model in the rotor frame
 * (d on the magnet flux): flux, torque and back-EMF.
 */
#ifndef FD_MODEL_PMSM_H
#define FD_MODEL_PMSM_H

#include "math/frames.h"

typedef struct {
  float pole_pairs;
  float rs;       /* [Ohm] */
  float ld, lq;   /* [H] */
  float lambda_m; /* [Vs] */
} pmsm_params_t;

/* lambda_dq = (Ld id + lambda_m, Lq iq) */
dq_t pmsm_flux(const pmsm_params_t *m, dq_t i);
/* T = 3/2 p (lambda_d iq - lambda_q id) */
float pmsm_torque(const pmsm_params_t *m, dq_t i);
/* q current giving torque t with id = 0 (SPM or id = 0 control) */
float pmsm_iq_for_torque(const pmsm_params_t *m, float t);
/* Steady-state voltage (back-EMF included) at electrical speed we [rad/s]:
 * vd = Rs id - we lambda_q, vq = Rs iq + we lambda_d */
dq_t pmsm_voltage_ss(const pmsm_params_t *m, dq_t i, float we);

#endif
