/*
 * cordic_bind.c - binds the core's trigonometry API (firmware/core/math/
 * fast_trig.h, and the Q31 CORDIC of math/cordic_q31.h) to the CORDIC
 * co-processor: these strong definitions replace
 * the core's weak software ones at link time (this file is an object of the
 * firmware executable, not an archive member). Host, SIL and QEMU (PIL)
 * builds keep the software versions. Accuracy: cordic.h (~6e-6 rad for
 * atan2, ~2e-6 for sin/cos), against 2e-6 rad / 2e-7 in software.
 * Selected by the CMake option FD_HW_CORDIC (default ON).
 *
 * In CCM SRAM, where the ISR's callers are, with cordic.h's sequences
 * inline: a call from the core lands on the register writes (a binding in
 * flash forwarding to a function in CCM SRAM cost two long-branch veneers
 * and a branch per call).
 */
#include "cordic.h"
#include "math/cordic_q31.h"
#include "math/fast_trig.h"

#define HOT __attribute__((section(".ccmram.text.cordic")))

HOT void fd_sincosf(float theta, float *s, float *c) {
  cordic_hw_sincosf(theta, s, c);
}

HOT float fd_atan2f(float y, float x) {
  return cordic_hw_atan2f(y, x);
}

HOT int32_t fd_cordic_atan2_q31(int32_t y, int32_t x, int32_t *mag) {
  return cordic_hw_atan2_q31(y, x, mag);
}
