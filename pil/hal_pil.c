/*
 * hal_pil.c - hal.h over a recorded input stream (see hal_pil.h).
 */
#include "hal_pil.h"
#include "hal_duty.h"

#include "hal.h"

static hal_adc_sample_t sample;
static float duty[3] = {0.5f, 0.5f, 0.5f};
static bool gates_on;
static bool hw_tripped;
static uint32_t time_us;

void hal_pil_set_input(const isr_stream_in_t *in) {
  sample.i_abc[0] = in->i_abc[0];
  sample.i_abc[1] = in->i_abc[1];
  sample.i_abc[2] = in->i_abc[2];
  sample.v_dc = in->v_dc;
  sample.v_star = in->v_star;
  sample.enc_angle = in->enc_angle;
  sample.enc_valid = (in->flags & ISR_IN_ENC_VALID) != 0u;
  hw_tripped = (in->flags & ISR_IN_HW_TRIPPED) != 0u;
  if (hw_tripped) {
    gates_on = false; /* the break input turns the gates off in hardware */
  }
  time_us = in->time_us;
}

void hal_pil_get_output(float d[3], bool *on) {
  d[0] = duty[0];
  d[1] = duty[1];
  d[2] = duty[2];
  *on = gates_on;
}

void hal_adc_read(hal_adc_sample_t *s) {
  *s = sample;
}

void hal_pwm_set_duty(float da, float db, float dc) {
  duty[0] = hal_duty_clamp01(da);
  duty[1] = hal_duty_clamp01(db);
  duty[2] = hal_duty_clamp01(dc);
}

void hal_pwm_enable(void) {
  if (!hw_tripped) {
    gates_on = true;
  }
}

void hal_pwm_disable(void) {
  gates_on = false;
}

bool hal_pwm_is_enabled(void) {
  return gates_on;
}

bool hal_can_send(const hal_can_frame_t *f) {
  (void)f;
  return true; /* the replay has no bus: frames are dropped */
}

bool hal_can_receive(hal_can_frame_t *f) {
  (void)f;
  return false;
}

uint32_t hal_time_us(void) {
  return time_us;
}

bool hal_fault_hw_tripped(void) {
  return hw_tripped;
}

void hal_fault_hw_clear(void) {
  hw_tripped = false;
}

void hal_watchdog_kick(void) {}
