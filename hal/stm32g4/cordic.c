/*
 * cordic.c - RM0440 section 17.3: functions "phase" (atan2 of x, y: two
 * arguments, result angle / pi) and "cosine" (arguments angle / pi and
 * modulus m, results m cos and m sin), q1.31 in and out (ARGSIZE = RESSIZE =
 * 0), SCALE = 0, PRECISION = 6. Zero-overhead mode: write the arguments to
 * WDATA (the second write starts the calculation), read RDATA (the bus
 * stalls until RRDY).
 */
#include "cordic.h"

#include <stdint.h>

#include "stm32g4_regs.h"

#define HOT       __attribute__((section(".ccmram.text.cordic")))
#define Q31       2147483648.0f
#define INV_Q31   (1.0f / 2147483648.0f)
#define PI_F      3.14159265358979f
#define INV_PI_F  (1.0f / 3.14159265358979f)
#define PRECISION 6u

void hal_cordic_init(void) {
  RCC->AHB1ENR |= RCC_AHB1ENR_CORDICEN;
  (void)RCC->AHB1ENR;
}

/* v in [-1, 1] -> q1.31, saturating at +1. */
HOT static int32_t to_q31(float v) {
  const float q = v * Q31;
  if (q >= Q31) {
    return INT32_MAX;
  }
  if (q <= -Q31) {
    return INT32_MIN;
  }
  return (int32_t)q;
}

HOT static float absf(float v) {
  return v < 0.0f ? -v : v;
}

HOT float cordic_hw_atan2f(float y, float x) {
  const float m = absf(x) > absf(y) ? absf(x) : absf(y);
  if (!(m > 0.0f) || !(m < 3.0e38f)) { /* zero, NaN, inf */
    return 0.0f;
  }
  const float k = 1.0f / m; /* |x|, |y| <= 1: the phase does not depend on the modulus */
  const int32_t qx = to_q31(x * k);
  const int32_t qy = to_q31(y * k);
  const uint32_t pm = hal_irq_save();
  CORDIC->CSR = (CORDIC_FUNC_PHASE << CORDIC_CSR_FUNC_Pos) |
                (PRECISION << CORDIC_CSR_PRECISION_Pos) | /* SCALE = 0 */
                CORDIC_CSR_NARGS; /* two arguments (x, y), one result, q1.31 */
  CORDIC->WDATA = (uint32_t)qx;
  CORDIC->WDATA = (uint32_t)qy;
  const int32_t r = (int32_t)CORDIC->RDATA;
  hal_irq_restore(pm);
  return (float)r * (INV_Q31 * PI_F);
}

HOT int32_t cordic_hw_atan2_q31(int32_t y, int32_t x, int32_t *mag) {
  if (x == 0 && y == 0) {
    if (mag != 0) {
      *mag = 0;
    }
    return 0;
  }
  const uint32_t pm = hal_irq_save();
  CORDIC->CSR = (CORDIC_FUNC_PHASE << CORDIC_CSR_FUNC_Pos) |
                (PRECISION << CORDIC_CSR_PRECISION_Pos) | /* SCALE = 0 */
                CORDIC_CSR_NARGS | CORDIC_CSR_NRES;       /* (x, y) -> (phase, modulus), q1.31 */
  CORDIC->WDATA = (uint32_t)x;
  CORDIC->WDATA = (uint32_t)y;
  const int32_t phase = (int32_t)CORDIC->RDATA;
  const int32_t modulus = (int32_t)CORDIC->RDATA;
  hal_irq_restore(pm);
  if (mag != 0) {
    /* the software CORDIC's gain, 1.6467602581 in q2.30 */
    *mag = (int32_t)(((int64_t)modulus * 1768255360LL) >> 30);
  }
  return phase;
}

HOT void cordic_hw_sincosf(float theta, float *s, float *c) {
  if (!(absf(theta) <= 1.0e6f)) { /* NaN, inf, huge */
    *s = 0.0f;
    *c = 1.0f;
    return;
  }
  /* angle / pi reduced to [-1, 1) */
  float t = theta * INV_PI_F;
  const int32_t n = (int32_t)(t * 0.5f);
  t -= 2.0f * (float)n;
  if (t >= 1.0f) {
    t -= 2.0f;
  } else if (t < -1.0f) {
    t += 2.0f;
  }
  const int32_t qa = to_q31(t);
  const uint32_t pm = hal_irq_save();
  CORDIC->CSR =                                 /* FUNC = 0: cosine */
      (PRECISION << CORDIC_CSR_PRECISION_Pos) | /* SCALE = 0 */
      CORDIC_CSR_NARGS | CORDIC_CSR_NRES;       /* (angle, modulus) -> (cos, sin) */
  CORDIC->WDATA = (uint32_t)qa;
  CORDIC->WDATA = 0x7FFFFFFFu; /* modulus 1 */
  const int32_t rc = (int32_t)CORDIC->RDATA;
  const int32_t rs = (int32_t)CORDIC->RDATA;
  hal_irq_restore(pm);
  *c = (float)rc * INV_Q31;
  *s = (float)rs * INV_Q31;
}
