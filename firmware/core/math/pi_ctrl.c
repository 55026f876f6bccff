/*
 * pi_ctrl.c - discrete PI with output limits and anti-windup.
 *
 * u = kp*e + integ + ff (limited), integ += ki*ts*e, and two rules:
 * 1. conditional integration: when the output would pass a limit with the
 *    error pushing into it, the integral grows only up to the value that puts
 *    the output on the limit (or not at all if it is already beyond);
 * 2. back-calculation: the integral is re-aligned into
 *    [out_min - ff - max(p, 0), out_max - ff - min(p, 0)], p = kp*e: while the
 *    error pulls the output back from a limit, kp*e + integ + ff is held on the
 *    limit (not beyond), so the output leaves saturation on the first step the
 *    error reverses; a large proportional term in the direction of the limit
 *    never drags the integral away (that would leave a long tail once the
 *    error shrinks), it only caps it at the limit minus the feed-forward.
 */
#include "math/pi_ctrl.h"

#include <math.h>

#include "math/fd_math.h"

static float pi_clamp(float x, float lo, float hi) {
  return (x > hi) ? hi : ((x < lo) ? lo : x);
}

void pi_ctrl_init(pi_ctrl_t *pi, float kp, float ki, float ts, float out_min, float out_max) {
  pi->kp = kp;
  pi->ki = ki;
  pi->ts = ts;
  pi->out_min = -INFINITY;
  pi->out_max = INFINITY;
  pi_ctrl_set_limits(pi, out_min, out_max);
  pi->integ = 0.0f;
}

/* Preset the integral (bumpless transfer: output = integ at zero error). */
void pi_ctrl_reset(pi_ctrl_t *pi, float integ) {
  pi->integ = fd_isfinite(integ) ? pi_clamp(integ, pi->out_min, pi->out_max) : 0.0f;
}

/* NaN limits are ignored (previous kept); crossed limits collapse to their
 * mean so that the output is still well defined. Infinite limits are fine. */
void pi_ctrl_set_limits(pi_ctrl_t *pi, float out_min, float out_max) {
  if (isnan(out_min) || isnan(out_max)) {
    return;
  }
  if (out_min > out_max) {
    const float mid = 0.5f * (out_min + out_max);
    out_min = mid;
    out_max = mid;
  }
  pi->out_min = out_min;
  pi->out_max = out_max;
}

float pi_ctrl_update(pi_ctrl_t *pi, float err, float ff) {
  if (!fd_isfinite(err)) {
    err = 0.0f; /* hold the integral, no proportional kick */
  }
  if (!fd_isfinite(ff)) {
    ff = 0.0f;
  }
  const float p = pi->kp * err;
  const float i_old = pi->integ;
  float integ = i_old + pi->ki * pi->ts * err;
  /* 1. conditional integration */
  const float to_max = pi->out_max - p - ff; /* integral that puts u on out_max */
  const float to_min = pi->out_min - p - ff;
  if (err > 0.0f && integ > to_max) {
    const float cap = (i_old > to_max) ? i_old : to_max;
    integ = (integ < cap) ? integ : cap;
  } else if (err < 0.0f && integ < to_min) {
    const float cap = (i_old < to_min) ? i_old : to_min;
    integ = (integ > cap) ? integ : cap;
  }
  /* 2. back-calculation: re-align against the limits */
  const float hi = pi->out_max - ff - ((p < 0.0f) ? p : 0.0f);
  const float lo = pi->out_min - ff - ((p > 0.0f) ? p : 0.0f);
  integ = pi_clamp(integ, lo, hi);
  if (fd_isfinite(integ)) {
    pi->integ = integ;
  }
  return pi_clamp(p + pi->integ + ff, pi->out_min, pi->out_max);
}
