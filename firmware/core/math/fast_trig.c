/*
 * fast_trig.c - portable single-precision sin/cos and atan2 (fast_trig.h).
 *
 * sin/cos: Cody-Waite reduction theta = n pi/2 + r, |r| <= pi/4 (about),
 * with pi/2 split in three floats C1 + C2 + C3 whose leading parts have 8
 * and 11 significant bits, so n C1 and n C2 are exact for |n| < 2^13 and
 * r carries no cancellation error; then the minimax polynomials of the
 * Cephes library (S. L. Moshier, sinf.c / cosf.c) on [-pi/4, pi/4]:
 *   sin r = r + r^3 (S1 + S2 r^2 + S3 r^4)
 *   cos r = 1 - r^2/2 + r^4 (K1 + K2 r^2 + K3 r^4)
 * and the quadrant n mod 4 selects and signs them.
 *
 * atan2: with ax = |x|, ay = |y| one of three ratios t, |t| <= tan(pi/8),
 * is formed with one division:
 *   ay <= tan(pi/8) ax:  atan(ay/ax)
 *   ax <= tan(pi/8) ay:  pi/2 + atan(-ax/ay)
 *   otherwise:           pi/4 + atan((ay - ax)/(ay + ax))
 * (atan(a) - atan(b) = atan((a - b)/(1 + ab)) with b = 1), then Cephes'
 * atanf polynomial atan t = t + t^3 (A1 + A2 t^2 + A3 t^4 + A4 t^6), and the
 * signs of x and y give the quadrant.
 */
#include "math/fast_trig.h"

#include <stdint.h>

#define FD_TRIG_2_OVER_PI 0.636619772367581f
#define FD_TRIG_C1        1.5703125f
#define FD_TRIG_C2        4.837512969970703125e-4f
#define FD_TRIG_C3        7.54978995489188216e-8f
#define FD_TRIG_S1        (-1.6666654611e-1f)
#define FD_TRIG_S2        8.3321608736e-3f
#define FD_TRIG_S3        (-1.9515295891e-4f)
#define FD_TRIG_K1        4.166664568298827e-2f
#define FD_TRIG_K2        (-1.388731625493765e-3f)
#define FD_TRIG_K3        2.443315711809948e-5f
#define FD_TRIG_TAN_PI_8  0.414213562373095f
#define FD_TRIG_PI        3.14159265358979f
#define FD_TRIG_PI_2      1.57079632679490f
#define FD_TRIG_PI_4      0.785398163397448f
#define FD_TRIG_A1        (-3.33329491539e-1f)
#define FD_TRIG_A2        1.99777106478e-1f
#define FD_TRIG_A3        (-1.38776856032e-1f)
#define FD_TRIG_A4        8.05374449538e-2f

__attribute__((weak)) void fd_sincosf(float theta, float *s, float *c) {
  if (!(fabsf(theta) <= FD_TRIG_ARG_MAX)) { /* also NaN */
    *s = 0.0f;
    *c = 1.0f;
    return;
  }
  /* n = round(theta 2/pi), half away from zero; |n| <= 636620 fits */
  const float q = theta * FD_TRIG_2_OVER_PI;
  const int32_t n = (int32_t)(q + ((q >= 0.0f) ? 0.5f : -0.5f));
  const float fn = (float)n;
  const float r = ((theta - fn * FD_TRIG_C1) - fn * FD_TRIG_C2) - fn * FD_TRIG_C3;
  const float z = r * r;
  const float sr = r + r * z * (FD_TRIG_S1 + z * (FD_TRIG_S2 + z * FD_TRIG_S3));
  const float cr = (1.0f - 0.5f * z) + z * z * (FD_TRIG_K1 + z * (FD_TRIG_K2 + z * FD_TRIG_K3));
  switch ((uint32_t)n & 3u) {
  case 0u:
    *s = sr;
    *c = cr;
    break;
  case 1u:
    *s = cr;
    *c = -sr;
    break;
  case 2u:
    *s = -sr;
    *c = -cr;
    break;
  default:
    *s = -cr;
    *c = sr;
    break;
  }
}

__attribute__((weak)) float fd_atan2f(float y, float x) {
  const float ax = fabsf(x);
  const float ay = fabsf(y);
  if (!(fd_isfinite(ax) && fd_isfinite(ay))) {
    return 0.0f;
  }
  float num;
  float den;
  float base;
  if (ay <= FD_TRIG_TAN_PI_8 * ax) {
    num = ay;
    den = ax;
    base = 0.0f;
  } else if (ax <= FD_TRIG_TAN_PI_8 * ay) {
    num = -ax;
    den = ay;
    base = FD_TRIG_PI_2;
  } else {
    num = ay - ax;
    den = ay + ax;
    base = FD_TRIG_PI_4;
  }
  if (!(den > 0.0f)) { /* (0, 0) */
    return 0.0f;
  }
  const float t = num / den;
  const float z = t * t;
  float a =
      base + (t + t * z * (FD_TRIG_A1 + z * (FD_TRIG_A2 + z * (FD_TRIG_A3 + z * FD_TRIG_A4))));
  if (x < 0.0f) {
    a = FD_TRIG_PI - a;
  }
  return (y < 0.0f) ? -a : a;
}
