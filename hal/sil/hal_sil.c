/*
 * hal_sil.c - hal.h over a hal_sil_t context (see hal_sil.h).
 */
#include "hal_sil.h"
#include "hal_duty.h"

#include <string.h>

static hal_sil_t *bound;

void hal_sil_init(hal_sil_t *h) {
  memset(h, 0, sizeof *h);
  h->duty[0] = h->duty[1] = h->duty[2] = 0.5f;
}

void hal_sil_bind(hal_sil_t *h) {
  bound = h;
}

void hal_adc_read(hal_adc_sample_t *s) {
  *s = bound->sample;
}

void hal_pwm_set_duty(float da, float db, float dc) {
  bound->duty[0] = hal_duty_clamp01(da);
  bound->duty[1] = hal_duty_clamp01(db);
  bound->duty[2] = hal_duty_clamp01(dc);
}

void hal_pwm_enable(void) {
  /* Like TIM1 MOE: cannot be set while the break input is latched. */
  if (!bound->hw_tripped) {
    bound->gates_on = true;
  }
}

void hal_pwm_disable(void) {
  bound->gates_on = false;
}

bool hal_pwm_is_enabled(void) {
  return bound->gates_on;
}

bool hal_sil_can_push(hal_sil_can_queue_t *q, const hal_can_frame_t *f) {
  if (q->head - q->tail >= HAL_SIL_CAN_QUEUE) {
    q->dropped++;
    return false;
  }
  q->frame[q->head % HAL_SIL_CAN_QUEUE] = *f;
  q->head++;
  return true;
}

bool hal_sil_can_pop(hal_sil_can_queue_t *q, hal_can_frame_t *f) {
  if (q->head == q->tail) {
    return false;
  }
  *f = q->frame[q->tail % HAL_SIL_CAN_QUEUE];
  q->tail++;
  return true;
}

bool hal_can_send(const hal_can_frame_t *f) {
  return hal_sil_can_push(&bound->can_tx, f);
}

bool hal_can_receive(hal_can_frame_t *f) {
  return hal_sil_can_pop(&bound->can_rx, f);
}

uint32_t hal_time_us(void) {
  return bound->time_us;
}

bool hal_fault_hw_tripped(void) {
  return bound->hw_tripped;
}

void hal_fault_hw_clear(void) {
  bound->hw_tripped = false;
}

void hal_watchdog_kick(void) {
  bound->watchdog_kicks++;
}
