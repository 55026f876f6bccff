/*
 * hal_duty.h - duty clamping shared by the HAL implementations that model
 * an ideal timer (hal/sil, pil): [0, 1], and NaN (compares false both
 * ways) maps to 0.5, i.e. no voltage. Board HALs clamp to their own
 * sampling window (hal/stm32g4/pwm_tim1.c).
 */
#ifndef FLUXDRIVE_HAL_DUTY_H
#define FLUXDRIVE_HAL_DUTY_H

static inline float hal_duty_clamp01(float x) {
  if (!(x >= 0.0f)) {
    return x < 0.0f ? 0.0f : 0.5f;
  }
  return x > 1.0f ? 1.0f : x;
}

#endif
