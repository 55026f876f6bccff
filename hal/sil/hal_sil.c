/*
 * hal_sil.c - hal.h over a hal_sil_t context (see hal_sil.h).
 */
#include "hal_sil.h"
#include "hal_pattern.h"

#include <string.h>

#define HAL_SIL_DUTY_TOL 1e-6f /* float rounding of off - on (hal_pwm_write) */

static hal_sil_t *bound;

void hal_sil_init(hal_sil_t *h, const hal_sil_board_t *board) {
  memset(h, 0, sizeof *h);
  h->caps.ts = board->ts;
  h->caps.t_count = board->timer_counts > 0u ? board->ts / (float)board->timer_counts : 0.0f;
  h->caps.dead_time = board->dead_time;
  h->caps.duty_min = board->duty_min;
  h->caps.duty_max = board->duty_max;
  h->clamp_lo = board->duty_min - HAL_SIL_DUTY_TOL;
  h->clamp_hi = board->duty_max + HAL_SIL_DUTY_TOL;
  h->caps.t_i = 0.0f;       /* the plant samples at the valley */
  h->caps.t_i_clear = 0.0f; /* an ideal sampler */
  h->caps.t_enc = 0.0f;
  h->caps.cpu_hz = 0.0f;
  h->caps.i_full_scale = board->i_full_scale;
  h->caps.v_full_scale = board->v_full_scale;
  h->caps.i_lsb = board->i_lsb;
  h->caps.features = HAL_CAP_ENCODER | HAL_CAP_STAR_POINT | HAL_CAP_I_ABC |
                     (board->asym_edges ? HAL_CAP_ASYM_EDGES : 0u);
  h->timer_counts = board->timer_counts;
  hal_pattern_init(&h->timer, &h->caps, board->timer_counts);
  h->watchdog_timeout_us = board->watchdog_ms * 1000u;
  h->pwm = hal_pwm_centred(0.5f, 0.5f, 0.5f);
}

void hal_sil_bind(hal_sil_t *h) {
  bound = h;
}

const hal_caps_t *hal_caps(void) {
  return &bound->caps;
}

void hal_adc_read(hal_sample_t *s) {
  *s = bound->sample;
}

void hal_pwm_write(const hal_pwm_t *p, hal_pwm_t *applied) {
  for (int x = 0; x < 3; ++x) { /* the range with its tolerance: hal_sil_init */
    const float d = p->off[x] - p->on[x];
    if (!(d >= bound->clamp_lo && d <= bound->clamp_hi)) {
      bound->pwm_clamped++;
      break;
    }
  }
  /* into a local first (its fields stay in registers), then stored to
   * both: copying bound->pwm right after its field-wise stores would load
   * 16 bytes over four fresh 4-byte stores, a store-forwarding stall on
   * x86 (9 % of foc_speed_load's time was spent here, perf) */
  hal_pwm_t out;
  hal_pattern_apply(&bound->timer, p, &out);
  bound->pwm = out;
  if (applied != NULL) {
    *applied = out;
  }
}

void hal_pwm_enable(void) {
  /* Like TIM1 MOE: cannot be set while the break input is latched. */
  if (!bound->hw_tripped) {
    bound->gates_on = true;
    bound->asc = false;
  }
}

void hal_pwm_disable(void) {
  bound->gates_on = false;
  bound->asc = false;
}

void hal_pwm_short(void) {
  if (!bound->hw_tripped) {
    bound->gates_on = false;
    bound->asc = true;
  }
}

bool hal_pwm_is_shorted(void) {
  return bound->asc;
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

uint32_t hal_fault_hw_source(void) {
  return bound->hw_source;
}

void hal_fault_hw_clear(void) {
  bound->hw_tripped = false;
  bound->hw_source = 0u;
}

void hal_watchdog_kick(void) {
  bound->watchdog_kicks++;
  bound->watchdog_last_us = bound->time_us;
}

bool hal_sil_watchdog_expired(const hal_sil_t *h, uint32_t now_us) {
  return h->watchdog_timeout_us > 0u && now_us - h->watchdog_last_us > h->watchdog_timeout_us;
}

bool hal_reset_by_watchdog(void) {
  return bound->reset_by_watchdog;
}

void hal_isr_stats(hal_isr_stats_t *st) {
  memset(st, 0, sizeof *st); /* no cycle counter on the host */
  st->overruns = bound->isr_overruns;
}

uint32_t hal_isr_overruns(void) {
  return bound->isr_overruns;
}
