/*
 * cordic.h - the STM32G4 CORDIC co-processor (RM0440 section 17) as float
 * atan2 and sin/cos.
 *
 * Accuracy: q1.31 arguments and results, PRECISION = 6 (24 iterations):
 * residual error about 2^-19 (RM0440 17.3.6 table of precision vs.
 * iterations): ~6e-6 rad for the angle, ~2e-6 for sin/cos. Each call takes
 * well under 0.5 us at 170 MHz; interrupts are masked during the few bus
 * cycles of one calculation, so any context may call it.
 *
 * The unit's configuration between calls is the cosine function's
 * (CORDIC_CSR_COSINE: arguments angle / pi and modulus, results m cos and
 * m sin, q1.31): hal_cordic_init sets it, so a sin/cos is two writes and
 * two reads; the phase functions (atan2) set theirs and put the cosine's
 * back before they unmask. The modulus is written at every sin/cos (two
 * arguments): with one argument (NARGS = 0) the unit keeps the last ARG2,
 * +1 after reset, but a phase calculation leaves its y there.
 *
 * HOW THE CORE BINDS TO IT (owned by the core; nothing is declared in
 * firmware/core/math by this HAL):
 *   1. firmware/core/math declares the portable API
 *        float fd_atan2f(float y, float x);
 *        void  fd_sincosf(float theta, float *s, float *c);
 *      and implements it in its own .c file with __attribute__((weak))
 *      (libm or a polynomial), so host/SIL builds are unchanged.
 *   2. The target build adds one file here, cordic_bind.c, with the strong
 *      definitions, in CCM SRAM beside their callers, which inline the
 *      sequences below (no call, no veneer between the core and the unit).
 *      It is an object of the firmware executable (not an archive member),
 *      so the linker takes the strong symbols and drops the weak ones.
 *   Call hal_cordic_init() before the first use (hal_stm32g4_init does).
 */
#ifndef FLUXDRIVE_STM32G4_CORDIC_H
#define FLUXDRIVE_STM32G4_CORDIC_H

#include <math.h>
#include <stdint.h>

#include "stm32g4_regs.h"

#define CORDIC_PRECISION 6u /* 24 iterations, four per cycle */
/* cosine: (angle / pi, modulus) -> (m cos, m sin), q1.31, SCALE = 0 */
#define CORDIC_CSR_COSINE                                                                          \
  ((CORDIC_FUNC_COSINE << CORDIC_CSR_FUNC_Pos) | (CORDIC_PRECISION << CORDIC_CSR_PRECISION_Pos) |  \
   CORDIC_CSR_NARGS | CORDIC_CSR_NRES)
/* phase: (x, y) -> (atan2(y, x) / pi[, modulus]), q1.31, SCALE = 0 */
#define CORDIC_CSR_PHASE                                                                           \
  ((CORDIC_FUNC_PHASE << CORDIC_CSR_FUNC_Pos) | (CORDIC_PRECISION << CORDIC_CSR_PRECISION_Pos) |   \
   CORDIC_CSR_NARGS)
#define CORDIC_Q31_MAX 0x7FFFFFFFu /* +1 in q1.31 (1 - 2^-31) */

/* The clock, and the cosine configuration (above). */
void hal_cordic_init(void);

/* v in [-1, 1] written to WDATA as q1.31: v 2^31 rounded towards zero,
 * +1 saturating to 1 - 2^-31 (NaN: 0), by one VCVT to fixed point with 31
 * fraction bits (ARMv7-M ARM, VCVT between floating point and fixed point:
 * saturating) straight from the FP register, and one store. */
static inline void cordic_write_q31(float v) {
  __asm__ volatile("vcvt.s32.f32 %1, %1, #31\n\tvstr %1, %0"
                   : "=Uv"(CORDIC->WDATA), "+t"(v)
                   :
                   : "memory");
}

/* The next result, q1.31 -> float (exact): RDATA read straight into an
 * FP register (the bus stalls until the result is ready) and one VCVT from
 * fixed point with 31 fraction bits. */
static inline float cordic_read_float(void) {
  float v;
  __asm__ volatile("vldr %0, %1\n\tvcvt.f32.s32 %0, %0, #31"
                   : "=t"(v)
                   : "Uv"(CORDIC->RDATA)
                   : "memory");
  return v;
}

/* atan2(y, x) in (-pi, pi]; 0 for (0, 0) and for non-finite inputs. */
static inline float cordic_hw_atan2f(float y, float x) {
  const float ax = fabsf(x), ay = fabsf(y);
  const float m = ax > ay ? ax : ay;
  if (!(m > 0.0f) || !(m < 3.0e38f)) { /* zero, NaN, inf */
    return 0.0f;
  }
  /* |x|, |y| <= 1: the phase does not depend on the modulus; the largest
   * is +1, which the conversion saturates */
  const float k = 1.0f / m;
  const uint32_t pm = hal_irq_save();
  CORDIC->CSR = CORDIC_CSR_PHASE;
  cordic_write_q31(x * k);
  cordic_write_q31(y * k); /* starts it; RDATA stalls the bus until the result */
  const int32_t r = (int32_t)CORDIC->RDATA;
  CORDIC->CSR = CORDIC_CSR_COSINE;
  hal_irq_restore(pm);
  return (float)r * (3.14159265358979f / 2147483648.0f);
}

/* sin and cos of theta [rad], any finite theta (reduced modulo 2 pi);
 * s = 0, c = 1 for non-finite theta or |theta| > 1e6 rad. */
static inline void cordic_hw_sincosf(float theta, float *s, float *c) {
  if (!(fabsf(theta) <= 1.0e6f)) { /* NaN, inf, huge */
    *s = 0.0f;
    *c = 1.0f;
    return;
  }
  /* t = theta / pi less the nearest even integer, in [-1, 1]: 1.5 2^24
   * added and taken away rounds t to an even integer (the floats' spacing
   * there is 2; |t| < 3.2e5 < 2^23), and t less it is exact (a multiple
   * of t's spacing, at most 1) */
  const float t = theta * (1.0f / 3.14159265358979f);
  const float even = (t + 25165824.0f) - 25165824.0f;
  const float a = t - even;
  const uint32_t pm = hal_irq_save();
  /* the cosine configuration (hal_cordic_init): the angle, +1 (pi)
   * saturating 1.5e-9 rad short, and the modulus 1, which starts it */
  cordic_write_q31(a);
  CORDIC->WDATA = CORDIC_Q31_MAX;
  const float rc = cordic_read_float(); /* m cos, then m sin */
  const float rs = cordic_read_float();
  hal_irq_restore(pm);
  *c = rc;
  *s = rs;
}

/* atan2(y, x) of integer inputs |x|, |y| < 2^30 in Q31 (pi = 2^31, the
 * unit's q1.31 phase), and in *mag (may be NULL) the modulus times the
 * software CORDIC's gain 1.6467602581 (firmware/core/math/cordic_q31.h's
 * conventions); (0, 0) gives 0 and 0. */
static inline int32_t cordic_hw_atan2_q31(int32_t y, int32_t x, int32_t *mag) {
  if (x == 0 && y == 0) {
    if (mag != 0) {
      *mag = 0;
    }
    return 0;
  }
  const uint32_t pm = hal_irq_save();
  CORDIC->CSR = CORDIC_CSR_PHASE | CORDIC_CSR_NRES; /* (x, y) -> (phase, modulus) */
  CORDIC->WDATA = (uint32_t)x;
  CORDIC->WDATA = (uint32_t)y;
  const int32_t phase = (int32_t)CORDIC->RDATA;
  const int32_t modulus = (int32_t)CORDIC->RDATA;
  CORDIC->CSR = CORDIC_CSR_COSINE;
  hal_irq_restore(pm);
  if (mag != 0) {
    /* the software CORDIC's gain, 1.6467602581 in q2.30 */
    *mag = (int32_t)(((int64_t)modulus * 1768255360LL) >> 30);
  }
  return phase;
}

#endif
