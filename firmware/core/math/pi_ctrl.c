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
 * The step itself is pi_ctrl_step (pi_ctrl.h), inline for the current
 * loop's symmetric limits (pi_ctrl_update_sym).
 */
#include "math/pi_ctrl.h"

#include <math.h>

#include "math/fd_math.h"

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
  pi->integ = fd_isfinite(integ) ? pi_ctrl_clamp(integ, pi->out_min, pi->out_max) : 0.0f;
}

/* NaN limits are ignored (previous kept); crossed limits collapse to their
 * mean so that the output is still well defined. Infinite limits are fine. */
void pi_ctrl_set_limits(pi_ctrl_t *pi, float out_min, float out_max) {
  pi_ctrl_limits_in(pi, out_min, out_max);
}

float pi_ctrl_update(pi_ctrl_t *pi, float err, float ff) {
  return pi_ctrl_step(pi, err, ff, pi->out_min, pi->out_max);
}
