/*
 * pi_ctrl.h - discrete PI regulator (forward-Euler integral) with output
 * limits and anti-windup by conditional integration plus back-calculation:
 * the integral never grows while the output is saturated in the direction
 * of the error, and it is re-aligned so that integ + ff stays within the
 * limits, and kp*e + integ + ff too whenever kp*e points away from the
 * limit (so the output leaves saturation as soon as the error reverses).
 * Details below (pi_ctrl_step) and in pi_ctrl.c.
 */
#ifndef FD_MATH_PI_CTRL_H
#define FD_MATH_PI_CTRL_H

#include <math.h>

#include "math/fd_math.h"

/* -Os would call the step from every update: inline, once per caller */
#if defined(__GNUC__)
#define PI_CTRL_INLINE static inline __attribute__((always_inline))
#else
#define PI_CTRL_INLINE static inline
#endif

typedef struct {
  float kp;      /* proportional gain */
  float ki;      /* integral gain [1/s] */
  float ts;      /* sampling period [s] */
  float out_min; /* output limits, out_min < out_max */
  float out_max;
  float integ; /* integral state (same unit as the output) */
} pi_ctrl_t;

void pi_ctrl_init(pi_ctrl_t *pi, float kp, float ki, float ts, float out_min, float out_max);
void pi_ctrl_reset(pi_ctrl_t *pi, float integ);
void pi_ctrl_set_limits(pi_ctrl_t *pi, float out_min, float out_max);
/* One step: err is ref - meas, ff a feed-forward added before the limit.
 * Returns the limited output. */
float pi_ctrl_update(pi_ctrl_t *pi, float err, float ff);

PI_CTRL_INLINE float pi_ctrl_clamp(float x, float lo, float hi) {
  return (x > hi) ? hi : ((x < lo) ? lo : x);
}

/* The rules of pi_ctrl_set_limits, in line for a caller that sets the
 * limits before every step (the speed loop, speed_ctrl_update): NaN
 * limits are ignored (the previous kept); crossed limits collapse to
 * their mean. */
PI_CTRL_INLINE void pi_ctrl_limits_in(pi_ctrl_t *pi, float out_min, float out_max) {
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

/* The step of pi_ctrl_update against the limits out_min <= out_max (not
 * NaN), the one implementation of its rules (pi_ctrl.c):
 *   u = kp e + integ + ff (limited), integ += ki ts e,
 * 1. conditional integration, 2. back-calculation. A non-finite error
 * holds the integral with no proportional kick; a non-finite feed-forward
 * counts as zero; a non-finite integral is never stored. */
PI_CTRL_INLINE float pi_ctrl_step(pi_ctrl_t *pi, float err, float ff, float out_min,
                                  float out_max) {
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
  const float to_max = out_max - p - ff; /* integral that puts u on out_max */
  const float to_min = out_min - p - ff;
  if (err > 0.0f && integ > to_max) {
    const float cap = (i_old > to_max) ? i_old : to_max;
    integ = (integ < cap) ? integ : cap;
  } else if (err < 0.0f && integ < to_min) {
    const float cap = (i_old < to_min) ? i_old : to_min;
    integ = (integ > cap) ? integ : cap;
  }
  /* 2. back-calculation: re-align against the limits */
  const float hi = out_max - ff - ((p < 0.0f) ? p : 0.0f);
  const float lo = out_min - ff - ((p > 0.0f) ? p : 0.0f);
  integ = pi_ctrl_clamp(integ, lo, hi);
  const float i_new = fd_isfinite(integ) ? integ : i_old; /* a non-finite one not stored */
  pi->integ = i_new;
  return pi_ctrl_clamp(p + i_new + ff, out_min, out_max);
}

/* pi_ctrl_set_limits(pi, -lim, lim) then pi_ctrl_update(pi, err, ff), for
 * a caller that knows lim finite and >= 0 (so neither of set_limits' cases,
 * a NaN or crossed limits, can arise): the limits stored and the step
 * inline, no call and no limit checks (the current loop's two axes). */
PI_CTRL_INLINE float pi_ctrl_update_sym(pi_ctrl_t *pi, float err, float ff, float lim) {
  pi->out_min = -lim;
  pi->out_max = lim;
  return pi_ctrl_step(pi, err, ff, -lim, lim);
}

#endif
