/*
 * angle_pll.c - type-2 angle-tracking PLL (PI on the wrapped angle error).
 * Closed loop (kp s + ki)/(s^2 + kp s + ki), kp = 2 wn, ki = wn^2: zero
 * steady-state error to a constant-speed ramp.
 */
#include "estimation/angle_pll.h"

#include "math/frames.h"

#include <math.h>

#include "math/fd_math.h"

FD_COLD void angle_pll_init(angle_pll_t *p, float bandwidth, float ts) {
  p->kp = 2.0f * bandwidth; /* zeta = 1 */
  p->ki = bandwidth * bandwidth;
  p->ts = ts;
  angle_pll_reset(p, 0.0f, 0.0f);
}

void angle_pll_reset(angle_pll_t *p, float theta, float omega) {
  p->theta = frames_wrap_pi(theta);
  p->omega = fd_isfinite(omega) ? omega : 0.0f;
  p->omega_rate = p->omega;
}

/* A non-finite measurement is skipped: the PLL coasts at its speed. */
void angle_pll_update(angle_pll_t *p, float theta_meas) {
  angle_pll_update_err(p, fd_isfinite(theta_meas) ? frames_wrap_pi(theta_meas - p->theta) : 0.0f);
}

void angle_pll_update_err(angle_pll_t *p, float e) {
  p->omega += p->ki * p->ts * e;
  p->omega_rate = p->omega + p->kp * e;
  p->theta = frames_wrap_pi(p->theta + p->ts * p->omega_rate);
}
