/*
 * frames.c - Clarke (amplitude-invariant) and Park transforms, angle wraps.
 */
#include "math/frames.h"

#include <math.h>

#define FRAMES_PI        3.14159265358979f
#define FRAMES_2PI       6.28318530717959f
#define FRAMES_INV_2PI   0.159154943091895f
#define FRAMES_INV_SQRT3 0.577350269189626f
#define FRAMES_SQRT3_2   0.866025403784439f

sincos_t frames_sincos(float theta) {
  sincos_t sc = {0.0f, 1.0f}; /* non-finite angle: identity rotation */
  if (isfinite(theta)) {
    sc.s = sinf(theta);
    sc.c = cosf(theta);
  }
  return sc;
}

/* alpha = (2a - b - c)/3, beta = (b - c)/sqrt(3): a balanced set of peak X
 * gives |x_ab| = X; the zero sequence is discarded. */
ab_t frames_clarke(abc_t x) {
  ab_t y;
  y.alpha = (2.0f * x.a - x.b - x.c) * (1.0f / 3.0f);
  y.beta = (x.b - x.c) * FRAMES_INV_SQRT3;
  return y;
}

/* With c = -a - b: alpha = a, beta = (a + 2b)/sqrt(3). */
ab_t frames_clarke2(float a, float b) {
  ab_t y;
  y.alpha = a;
  y.beta = (a + 2.0f * b) * FRAMES_INV_SQRT3;
  return y;
}

/* Inverse amplitude-invariant Clarke with zero zero-sequence. */
abc_t frames_clarke_inv(ab_t x) {
  abc_t y;
  y.a = x.alpha;
  y.b = -0.5f * x.alpha + FRAMES_SQRT3_2 * x.beta;
  y.c = -0.5f * x.alpha - FRAMES_SQRT3_2 * x.beta;
  return y;
}

/* x_dq = e^{-j theta} x_ab */
dq_t frames_park(ab_t x, sincos_t sc) {
  dq_t y;
  y.d = sc.c * x.alpha + sc.s * x.beta;
  y.q = -sc.s * x.alpha + sc.c * x.beta;
  return y;
}

/* x_ab = e^{+j theta} x_dq */
ab_t frames_park_inv(dq_t x, sincos_t sc) {
  ab_t y;
  y.alpha = sc.c * x.d - sc.s * x.q;
  y.beta = sc.s * x.d + sc.c * x.q;
  return y;
}

/* Non-finite input gives 0. Constant time (no loops). */
float frames_wrap_pi(float theta) {
  /* Fast paths: nearly every caller is within one turn of the range. */
  if (theta >= -FRAMES_PI && theta < FRAMES_PI) {
    return theta;
  }
  if (theta >= FRAMES_PI && theta < 3.0f * FRAMES_PI) {
    float r = theta - FRAMES_2PI;
    return r < FRAMES_PI ? r : -FRAMES_PI;
  }
  if (theta < -FRAMES_PI && theta >= -3.0f * FRAMES_PI) {
    float r = theta + FRAMES_2PI;
    return r >= -FRAMES_PI ? r : -FRAMES_PI;
  }
  if (!isfinite(theta)) {
    return 0.0f;
  }
  float r = theta - FRAMES_2PI * floorf((theta + FRAMES_PI) * FRAMES_INV_2PI);
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
  if (!isfinite(theta)) {
    return 0.0f;
  }
  float r = theta - FRAMES_2PI * floorf(theta * FRAMES_INV_2PI);
  if (r >= FRAMES_2PI || r < 0.0f) {
    r = 0.0f;
  }
  return r;
}
