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
 * HOW THE CORE WILL BIND TO IT (owned by the core; nothing is declared in
 * firmware/core/math by this HAL):
 *   1. firmware/core/math declares the portable API
 *        float fd_atan2f(float y, float x);
 *        void  fd_sincosf(float theta, float *s, float *c);
 *      and implements it in its own .c file with __attribute__((weak))
 *      (libm or a polynomial), so host/SIL builds are unchanged.
 *   2. The target build adds one file here, cordic_bind.c, with the strong
 *      definitions that forward to cordic_hw_atan2f / cordic_hw_sincosf.
 *      It is an object of the firmware executable (not an archive member),
 *      so the linker takes the strong symbols and drops the weak ones.
 *   Alternative without weak symbols: a CMake option selecting which .c
 *   provides fd_atan2f/fd_sincosf at link time (one definition per build).
 *   Call hal_cordic_init() before the first use (hal_stm32g4_init does).
 */
#ifndef FLUXDRIVE_STM32G4_CORDIC_H
#define FLUXDRIVE_STM32G4_CORDIC_H

#include <stdint.h>

void hal_cordic_init(void);
/* atan2(y, x) in (-pi, pi]; 0 for (0, 0) and for non-finite inputs. */
float cordic_hw_atan2f(float y, float x);
/* sin and cos of theta [rad], any finite theta (reduced modulo 2 pi);
 * s = 0, c = 1 for non-finite theta or |theta| > 1e6 rad. */
void cordic_hw_sincosf(float theta, float *s, float *c);
/* atan2(y, x) of integer inputs |x|, |y| < 2^30 in Q31 (pi = 2^31, the
 * unit's q1.31 phase), and in *mag (may be NULL) the modulus times the
 * software CORDIC's gain 1.6467602581 (firmware/core/math/cordic_q31.h's
 * conventions); (0, 0) gives 0 and 0. */
int32_t cordic_hw_atan2_q31(int32_t y, int32_t x, int32_t *mag);

#endif
