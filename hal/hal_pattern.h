/*
 * hal_pattern.h - what a timer does with a requested PWM pattern, shared
 * by the HAL implementations that model a timer (hal/sil, pil): every leg
 * limited to the board's duty range and, without HAL_CAP_ASYM_EDGES,
 * centred; edges rounded to the timer's compare steps (counts per period,
 * 0 = exact). A NaN request gives the middle of the range (no voltage).
 * The STM32G4 HAL does the same with its registers (hal/stm32g4/pwm_tim1.c).
 */
#ifndef FLUXDRIVE_HAL_PATTERN_H
#define FLUXDRIVE_HAL_PATTERN_H

#include <stdint.h>

#include "hal.h"

static inline float hal_pattern_clamp(float x, float lo, float hi) {
  if (!(x >= lo)) {
    return x < lo ? lo : 0.5f * (lo + hi); /* NaN: the middle */
  }
  return x > hi ? hi : x;
}

/* To the nearest count, as the board's duty_to_ccr (x >= 0 here: a clamped
 * duty or an edge inside the period; no libm call in the ISR). */
static inline float hal_pattern_round(float x, uint32_t counts) {
  if (counts == 0u) {
    return x;
  }
  const float n = x > 0.0f ? x * (float)counts + 0.5f : 0.0f;
  return (float)(uint32_t)n / (float)counts;
}

static inline void hal_pattern_apply(const hal_pwm_t *p, const hal_caps_t *caps, uint32_t counts,
                                     hal_pwm_t *out) {
  *out = *p;
  for (int x = 0; x < 3; ++x) {
    const float d = hal_pattern_round(
        hal_pattern_clamp(p->off[x] - p->on[x], caps->duty_min, caps->duty_max), counts);
    if ((caps->features & HAL_CAP_ASYM_EDGES) != 0u && p->on[x] >= 0.0f && p->off[x] <= 1.0f) {
      /* the edges as asked, the pulse limited from its end; 2 counts per
       * compare step of a centre-aligned timer */
      out->on[x] = hal_pattern_round(p->on[x], 2u * counts);
      out->off[x] = out->on[x] + d;
    } else {
      out->on[x] = 0.5f * (1.0f - d);
      out->off[x] = 0.5f * (1.0f + d);
    }
  }
  if ((caps->features & HAL_CAP_STAR_POINT) == 0u) {
    out->n_star = 0u;
  }
}

#endif
