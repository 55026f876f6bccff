/*
 * cordic_q31.h - a portable fixed-point CORDIC in vectoring mode: atan2 and
 * the magnitude of a vector, the angle in Q31 (pi = 2^31, the STM32G4
 * CORDIC's q1.31 format), for the position algorithms of Direct Flux
 * Control (Fabbri 2022, chapter 3: the angle of the DFC / IVD vector).
 *
 * Arithmetic: integer shifts and adds only (the same result on every
 * target); inputs |x|, |y| < 2^30 (the CORDIC gain 1.647 keeps the
 * iterates inside int32). FD_CORDIC_ITER = 26 iterations: the residual
 * angle after them is below atan(2^-25) = 3.0e-8 rad, the rounding of the
 * shifts adds about 26 * 2^-29 of the vector's magnitude in angle. With
 * inputs normalised to [2^28, 2^29) the Q31 angle is within 1e-7 rad of
 * atan2; the float entry point adds the float's own resolution (2.4e-7 rad
 * near pi): within 4e-7 rad (tests/core/test_cordic_q31.c, against double
 * libm over a dense grid, the axes, tiny, subnormal and huge vectors).
 */
#ifndef FD_MATH_CORDIC_Q31_H
#define FD_MATH_CORDIC_Q31_H

#include <stdint.h>

#define FD_CORDIC_ITER 26
/* radians per Q31 unit: pi / 2^31 */
#define FD_CORDIC_Q31_RAD 1.4629180792671596e-9f

/* The angle table: atan(2^-i) in Q31, i = 0 .. FD_CORDIC_ITER - 1. */
extern const int32_t fd_cordic_atan_q31[FD_CORDIC_ITER];

/* atan2(y, x) in Q31 ([-2^31, 2^31): -pi .. pi - 2^-31 pi; the direction
 * of -x, y = 0 is -2^31, i.e. pi modulo 2 pi); *mag (may be NULL) gets
 * the magnitude times the CORDIC gain 1.6467602581. (0, 0) gives 0.
 * Requires |x|, |y| < 2^30. */
int32_t fd_cordic_atan2_q31(int32_t y, int32_t x, int32_t *mag);
/* (Defined weak: the STM32G4 build binds the CORDIC co-processor's phase
 * and modulus function, hal/stm32g4/cordic_bind.c, with the same
 * conventions; its precision is the hardware's, ~6e-6 rad, cordic.h.) */

/* Float entry point: atan2(y, x) in [-pi, pi] by the Q31 CORDIC after an
 * exact power-of-two normalisation (no libm); +pi for y = +-0, x < 0 (as
 * fd_atan2f); 0 for (0, 0) and for non-finite inputs. */
float fd_cordic_atan2f(float y, float x);

#endif
