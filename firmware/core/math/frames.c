/*
 * frames.c - the out-of-line parts of the angle wraps (math/frames.h holds
 * the Clarke / Park transforms and the wraps' fast paths, inline).
 */
#include "math/frames.h"

#include <math.h>
#include <stdint.h>

#include "math/fd_math.h"

#define FRAMES_INV_2PI 0.159154943091895f

/* Any input (frames_wrap_pi() calls it beyond one turn either side). */
float frames_wrap_pi_slow(float theta) {
  /* r = theta - 2 pi floor(t): the floor by a conversion to an integer
   * (exact, same value as floorf) while |t| < 2^30, floorf beyond. A
   * non-finite theta gives a non-finite t, which fails the first test: its
   * check is off the usual path (a finite theta always gives a finite t) */
  const float t = (theta + FRAMES_PI) * FRAMES_INV_2PI;
  float fl;
  if (fabsf(t) < 1073741824.0f) {
    const int32_t n = (int32_t)t; /* towards zero */
    fl = (float)n;
    if (fl > t) {
      fl -= 1.0f;
    }
  } else {
    if (!fd_isfinite(theta)) {
      return 0.0f;
    }
    fl = floorf(t);
  }
  float r = theta - FRAMES_2PI * fl;
  /* rounding can land just outside the half-open interval */
  if (r >= FRAMES_PI) {
    r -= FRAMES_2PI;
  }
  if (r < -FRAMES_PI) {
    r = -FRAMES_PI;
  }
  return r;
}

float frames_wrap_2pi(float theta) {
  if (!fd_isfinite(theta)) {
    return 0.0f;
  }
  float r = theta - FRAMES_2PI * floorf(theta * FRAMES_INV_2PI);
  if (r >= FRAMES_2PI || r < 0.0f) {
    r = 0.0f;
  }
  return r;
}
