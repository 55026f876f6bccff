/*
 * frames.h - vector types and the Clarke / Park transforms.
 * Amplitude-invariant Clarke (a 3-phase set of peak I gives |i_ab| = I).
 * Park rotates by the electrical angle theta: x_dq = e^{-j theta} x_ab.
 */
#ifndef FD_MATH_FRAMES_H
#define FD_MATH_FRAMES_H

#include "math/fast_trig.h"

typedef struct {
  float a, b, c;
} abc_t;

typedef struct {
  float alpha, beta;
} ab_t;

typedef struct {
  float d, q;
} dq_t;

/* sin and cos of one angle, computed once and shared by Park and inverse. */
typedef struct {
  float s, c;
} sincos_t;

/* The transforms are static inline (a few multiply-adds each: a call would
 * cost more than the body in the ISR); the angle wraps' rare slow paths and
 * frames_wrap_2pi stay in frames.c. */

#define FRAMES_PI        3.14159265358979f
#define FRAMES_2PI       6.28318530717959f
#define FRAMES_INV_SQRT3 0.577350269189626f
#define FRAMES_SQRT3_2   0.866025403784439f

/* sin and cos of theta (math/fast_trig.h); a non-finite angle gives the
 * identity rotation (s = 0, c = 1). */
static inline sincos_t frames_sincos(float theta) {
  sincos_t sc;
  fd_sincosf(theta, &sc.s, &sc.c);
  return sc;
}

/* alpha = (2a - b - c)/3, beta = (b - c)/sqrt(3): a balanced set of peak X
 * gives |x_ab| = X; the zero sequence is discarded. */
static inline ab_t frames_clarke(abc_t x) {
  ab_t y;
  y.alpha = (2.0f * x.a - x.b - x.c) * (1.0f / 3.0f);
  y.beta = (x.b - x.c) * FRAMES_INV_SQRT3;
  return y;
}

/* Clarke from two phases, assuming a + b + c = 0 (two-shunt boards).
 * With c = -a - b: alpha = a, beta = (a + 2b)/sqrt(3). */
static inline ab_t frames_clarke2(float a, float b) {
  ab_t y;
  y.alpha = a;
  y.beta = (a + 2.0f * b) * FRAMES_INV_SQRT3;
  return y;
}

/* Inverse amplitude-invariant Clarke with zero zero-sequence. */
static inline abc_t frames_clarke_inv(ab_t x) {
  abc_t y;
  y.a = x.alpha;
  y.b = -0.5f * x.alpha + FRAMES_SQRT3_2 * x.beta;
  y.c = -0.5f * x.alpha - FRAMES_SQRT3_2 * x.beta;
  return y;
}

/* x_dq = e^{-j theta} x_ab */
static inline dq_t frames_park(ab_t x, sincos_t sc) {
  dq_t y;
  y.d = sc.c * x.alpha + sc.s * x.beta;
  y.q = -sc.s * x.alpha + sc.c * x.beta;
  return y;
}

/* x_ab = e^{+j theta} x_dq */
static inline ab_t frames_park_inv(dq_t x, sincos_t sc) {
  ab_t y;
  y.alpha = sc.c * x.d - sc.s * x.q;
  y.beta = sc.s * x.d + sc.c * x.q;
  return y;
}

/* e^{j(a + b)} from e^{j a} and e^{j b} (one complex product; no sin/cos). */
static inline sincos_t frames_sincos_add(sincos_t a, sincos_t b) {
  sincos_t y;
  y.s = a.s * b.c + a.c * b.s;
  y.c = a.c * b.c - a.s * b.s;
  return y;
}

/* e^{j(a - b)} from e^{j a} and e^{j b}. */
static inline sincos_t frames_sincos_sub(sincos_t a, sincos_t b) {
  sincos_t y;
  y.s = a.s * b.c - a.c * b.s;
  y.c = a.c * b.c + a.s * b.s;
  return y;
}

/* frames_wrap_pi() beyond one turn either side, and non-finite input. */
float frames_wrap_pi_slow(float theta);

/* Wrap an angle to [-pi, pi). Non-finite input gives 0. Constant time. */
static inline float frames_wrap_pi(float theta) {
  /* Fast paths: nearly every caller is within one turn of the range. The
   * first as |theta| < pi: one constant and one compare (theta = -pi, in
   * the range, takes the slow path, which returns it unchanged) */
  if (fabsf(theta) < FRAMES_PI) {
    return theta;
  }
  /* Then theta < 3 pi first: an angle of many turns (the encoder's
   * pole_pairs times the mechanical angle, 89 % of the Rubino 2020 SPM's
   * samples) fails it and goes to the general path after one compare
   * (issue 24 point 8); the branches' results are as before */
  if (!(theta < 3.0f * FRAMES_PI)) {
    return frames_wrap_pi_slow(theta);
  }
  if (theta >= FRAMES_PI) {
    const float r = theta - FRAMES_2PI;
    return r < FRAMES_PI ? r : -FRAMES_PI;
  }
  if (theta < -FRAMES_PI && theta >= -3.0f * FRAMES_PI) {
    const float r = theta + FRAMES_2PI;
    return r >= -FRAMES_PI ? r : -FRAMES_PI;
  }
  return frames_wrap_pi_slow(theta);
}

/* Wrap an angle to [0, 2 pi). Non-finite input gives 0. */
float frames_wrap_2pi(float theta);

#endif
