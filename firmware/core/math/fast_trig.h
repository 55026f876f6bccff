/*
 * fast_trig.h - single-precision sin/cos, atan2 and asin for the ISR path,
 * in portable C (no libm call): the same machine-independent arithmetic on
 * the host (SIL) and on the MCU, so both builds compute the same angles.
 *
 * This is the portable API that hal/stm32g4/cordic.h anticipates:
 * fd_sincosf() and fd_atan2f() are defined __attribute__((weak)) in
 * fast_trig.c, so a board build may bind them to the CORDIC co-processor
 * by linking strong definitions (cordic_bind.c, an object of the
 * executable). The semantics below are the ones cordic.h documents.
 *
 * Accuracy (tests/core/test_fast_trig.c, against double-precision libm on
 * dense grids):
 *   fd_sincosf: |error| <= 2e-7 for |theta| <= 4 pi; the reduction is exact
 *     for |theta| < 8192 pi/2 (12868 rad), beyond it the error grows like
 *     the float spacing of theta itself.
 *   fd_atan2f:  |error| <= 2e-6 rad (measured a few 1e-7).
 *   fd_asinf:   |error| <= 2e-6 rad.
 */
#ifndef FD_MATH_FAST_TRIG_H
#define FD_MATH_FAST_TRIG_H

#include <math.h>

#include "math/fd_math.h"

/* Arguments beyond this magnitude give s = 0, c = 1 (as the CORDIC binding). */
#define FD_TRIG_ARG_MAX 1.0e6f

/* sin and cos of theta [rad]. Non-finite theta or |theta| > FD_TRIG_ARG_MAX:
 * s = 0, c = 1 (identity rotation). Constant time: one bounded reduction to
 * a quadrant, then minimax polynomials on [-pi/4, pi/4]. */
void fd_sincosf(float theta, float *s, float *c);

/* atan2(y, x) in [-pi, pi] (pi rounded to float; y = +-0 with x < 0 gives
 * +pi, a tiny negative y with x < 0 rounds onto -pi as in libm); 0 for
 * (0, 0) and for non-finite inputs. An octant reduction to |t| <= tan(pi/8)
 * with a single division, then a minimax polynomial. */
float fd_atan2f(float y, float x);

/* asin(s) in [-pi/2, pi/2] as atan2(s, sqrt(1 - s^2)); s is first clamped
 * to [-1, 1] by fd_clampf (a NaN s gives -pi/2). */
static inline float fd_asinf(float s) {
  const float x = fd_clampf(s, -1.0f, 1.0f);
  return fd_atan2f(x, sqrtf((1.0f - x) * (1.0f + x)));
}

#endif
