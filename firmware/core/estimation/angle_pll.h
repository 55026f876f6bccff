/*
 * angle_pll.h - angle-tracking PLL: from a measured (quantised, noisy)
 * electrical angle to a filtered angle and speed. Type-2 loop,
 * error e = wrap(theta_meas - theta), w += ki*Ts*e, theta += Ts*(w + kp*e),
 * with kp = 2*zeta*wn, ki = wn^2 (zeta = 1: critically damped).
 */
#ifndef FD_ESTIMATION_ANGLE_PLL_H
#define FD_ESTIMATION_ANGLE_PLL_H

typedef struct {
  float kp, ki, ts;
  float theta;      /* estimated angle [rad], wrapped to [-pi, pi) */
  float omega;      /* estimated speed, the loop integrator [rad/s]: smooth,
                      lags by kp/ki * acceleration under a constant acceleration */
  float omega_rate; /* rate of theta, omega + kp e [rad/s]: no lag under
                       acceleration, noisier (average it before use) */
} angle_pll_t;

void angle_pll_init(angle_pll_t *p, float bandwidth, float ts);
void angle_pll_reset(angle_pll_t *p, float theta, float omega);
void angle_pll_update(angle_pll_t *p, float theta_meas);
/* The same with the error e = wrap(theta_meas - theta) the caller already
 * has (a position source's health is |e|: one wrap, not two). */
void angle_pll_update_err(angle_pll_t *p, float e);

#endif
