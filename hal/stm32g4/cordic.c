/*
 * cordic.c - RM0440 section 17.3: the unit's clock and its configuration
 * between calls, the cosine function (cordic.h: CORDIC_CSR_COSINE); the
 * calculations themselves are cordic.h's inline sequences: functions
 * "phase" (atan2 of x, y: two arguments, result angle / pi) and "cosine"
 * (arguments angle / pi and modulus m, results m cos and m sin), q1.31 in
 * and out (ARGSIZE = RESSIZE = 0), SCALE = 0, PRECISION = 6. Zero-overhead
 * mode: write the arguments to WDATA (the second write starts the
 * calculation), read RDATA (the bus stalls until RRDY).
 */
#include "cordic.h"

#include <stdint.h>

#include "stm32g4_regs.h"

void hal_cordic_init(void) {
  RCC->AHB1ENR |= RCC_AHB1ENR_CORDICEN;
  (void)RCC->AHB1ENR;
  CORDIC->CSR = CORDIC_CSR_COSINE;
}
