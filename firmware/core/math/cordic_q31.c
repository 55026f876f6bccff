/*
 * cordic_q31.c - portable fixed-point CORDIC (vectoring): atan2 in Q31.
 */
#include "math/cordic_q31.h"

#include <string.h>

#include "math/fd_math.h"

/* round(atan(2^-i) * 2^31 / pi), i = 0 .. 25 (checked against libm by
 * tests/core/test_cordic_q31.c) */
const int32_t fd_cordic_atan_q31[FD_CORDIC_ITER] = {
    536870912, 316933406, 167458907, 85004756, 42667331, 21354465, 10679838, 5340245, 2670163,
    1335087,   667544,    333772,    166886,   83443,    41722,    20861,    10430,   5215,
    2608,      1304,      652,       326,      163,      81,       41,       20};

/* weak: the STM32G4 build binds the CORDIC co-processor (hal/stm32g4/
 * cordic_bind.c), host, SIL and PIL keep this one */
__attribute__((weak)) int32_t fd_cordic_atan2_q31(int32_t y, int32_t x, int32_t *mag) {
  /* into the right half-plane: a rotation by pi, the angle offset
   * (modular: +pi and -pi are the same Q31 word, 2^31) */
  if (x == 0 && y == 0) {
    if (mag != NULL) {
      *mag = 0;
    }
    return 0;
  }
  uint32_t z = 0u;
  if (x < 0) {
    x = -x;
    y = -y;
    z = 0x80000000u;
  }
  /* unrolled: constant shifts become the shifted operands of the adds
   * (one Thumb-2 instruction each), no loop counter (the same arithmetic,
   * bit for bit, as the loop over i) */
#define FD_CORDIC_STEP(i)                                                                          \
  do {                                                                                             \
    const int32_t xs = x >> (i); /* arithmetic shift: floor division by 2^i */                     \
    const int32_t ys = y >> (i);                                                                   \
    if (y > 0) {                                                                                   \
      x += ys;                                                                                     \
      y -= xs;                                                                                     \
      z += (uint32_t)fd_cordic_atan_q31[i];                                                        \
    } else {                                                                                       \
      x -= ys;                                                                                     \
      y += xs;                                                                                     \
      z -= (uint32_t)fd_cordic_atan_q31[i];                                                        \
    }                                                                                              \
  } while (0)
  FD_CORDIC_STEP(0);
  FD_CORDIC_STEP(1);
  FD_CORDIC_STEP(2);
  FD_CORDIC_STEP(3);
  FD_CORDIC_STEP(4);
  FD_CORDIC_STEP(5);
  FD_CORDIC_STEP(6);
  FD_CORDIC_STEP(7);
  FD_CORDIC_STEP(8);
  FD_CORDIC_STEP(9);
  FD_CORDIC_STEP(10);
  FD_CORDIC_STEP(11);
  FD_CORDIC_STEP(12);
  FD_CORDIC_STEP(13);
  FD_CORDIC_STEP(14);
  FD_CORDIC_STEP(15);
  FD_CORDIC_STEP(16);
  FD_CORDIC_STEP(17);
  FD_CORDIC_STEP(18);
  FD_CORDIC_STEP(19);
  FD_CORDIC_STEP(20);
  FD_CORDIC_STEP(21);
  FD_CORDIC_STEP(22);
  FD_CORDIC_STEP(23);
  FD_CORDIC_STEP(24);
  FD_CORDIC_STEP(25);
#undef FD_CORDIC_STEP
  _Static_assert(FD_CORDIC_ITER == 26, "one FD_CORDIC_STEP per iteration");
  if (mag != NULL) {
    *mag = x;
  }
  int32_t a;
  memcpy(&a, &z, sizeof a); /* two's complement: the angle in [-pi, pi) */
  return a;
}

/* The exponent e of |v| (v normal, non-zero): 2^(e-1) <= |v| < 2^e. */
static int cordic_exponent(float v) {
  uint32_t b;
  memcpy(&b, &v, sizeof b);
  return (int)((b >> 23) & 0xFFu) - 126;
}

/* 2^k as a float for -126 <= k <= 127. */
static float cordic_pow2(int k) {
  const uint32_t b = (uint32_t)(k + 127) << 23;
  float f;
  memcpy(&f, &b, sizeof f);
  return f;
}

float fd_cordic_atan2f(float y, float x) {
  if (!(fd_isfinite(x) && fd_isfinite(y))) {
    return 0.0f;
  }
  float ax = x < 0.0f ? -x : x;
  float ay = y < 0.0f ? -y : y;
  float m = ax > ay ? ax : ay;
  if (!(m > 0.0f)) {
    return 0.0f;
  }
  if (!(ay > 0.0f)) {
    return x < 0.0f ? 3.14159265358979f : 0.0f; /* on the x axis: exact, +pi as libm for y = +-0 */
  }
  /* subnormal vectors: lift by 2^64 first (the angle is scale-free) */
  if (m < 1.17549435e-38f) {
    x *= 1.8446744e19f;
    y *= 1.8446744e19f;
    ax = x < 0.0f ? -x : x;
    ay = y < 0.0f ? -y : y;
    m = ax > ay ? ax : ay;
  }
  /* scale the larger component into [2^28, 2^29): exact (a power of two),
   * in two factors so that each stays a normal float */
  const int k = 29 - cordic_exponent(m);
  const int k1 = k / 2;
  const float s1 = cordic_pow2(k1);
  const float s2 = cordic_pow2(k - k1);
  const int32_t xi = (int32_t)(x * s1 * s2);
  const int32_t yi = (int32_t)(y * s1 * s2);
  int32_t a = fd_cordic_atan2_q31(yi, xi, NULL);
  /* next to the -x axis the sign of y picks the side of pi, as libm, even
   * where the scaled y rounded to 0 or the iterations crossed pi */
  if (x < 0.0f && a < 0 && y > 0.0f) {
    return 3.14159265358979f;
  }
  if (x < 0.0f && a > 0 && y < 0.0f) {
    return -3.14159265358979f;
  }
  return (float)a * FD_CORDIC_Q31_RAD;
}
