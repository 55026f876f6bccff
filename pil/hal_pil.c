/*
 * hal_pil.c - hal.h over a recorded input stream (see hal_pil.h).
 */
#include "hal_pil.h"
#include "hal_pattern.h"

#include "hal.h"

static hal_caps_t caps;
static hal_pattern_t timer; /* the timer model of caps (hal_pattern.h) */
static hal_sample_t sample;
static hal_pwm_t pwm;
static bool gates_on;
static bool hw_tripped;
static bool shorted;      /* hal_pwm_short: not in the stream (no PIL scenario trips) */
static uint32_t in_flags; /* the record's flags (the break's source, read on a trip) */
static uint32_t time_us;

void hal_pil_set_caps(const hal_caps_t *c, uint32_t timer_counts) {
  caps = *c;
  hal_pattern_init(&timer, c, timer_counts);
  pwm = hal_pwm_centred(0.5f, 0.5f, 0.5f);
}

void hal_pil_set_input(const isr_stream_in_t *in) {
  sample.i_abc[0] = in->i_abc[0];
  sample.i_abc[1] = in->i_abc[1];
  sample.i_abc[2] = in->i_abc[2];
  sample.v_dc = in->v_dc;
  sample.t_i = in->t_i;
  sample.v_star[0] = in->v_star[0];
  sample.v_star[1] = in->v_star[1];
  sample.t_star[0] = in->t_star[0];
  sample.t_star[1] = in->t_star[1];
  sample.n_star = (uint8_t)in->n_star;
  sample.test_vector = (uint8_t)in->test_vector;
  sample.enc_angle = in->enc_angle;
  sample.t_enc = in->t_enc;
  sample.enc_valid = (in->flags & ISR_IN_ENC_VALID) != 0u;
  sample.valid = (in->flags & ISR_IN_VALID) != 0u;
  hw_tripped = (in->flags & ISR_IN_HW_TRIPPED) != 0u;
  in_flags = in->flags;
  if (hw_tripped) {
    gates_on = false; /* the break input turns the gates off in hardware */
    shorted = false;
  }
  time_us = in->time_us;
}

void hal_pil_get_output(float d[3], bool *on) {
  d[0] = pwm.off[0] - pwm.on[0];
  d[1] = pwm.off[1] - pwm.on[1];
  d[2] = pwm.off[2] - pwm.on[2];
  *on = gates_on;
}

const hal_caps_t *hal_caps(void) {
  return &caps;
}

void hal_adc_read(hal_sample_t *s) {
  *s = sample;
}

void hal_pwm_write(const hal_pwm_t *p, hal_pwm_t *applied) {
  hal_pattern_apply(&timer, p, &pwm);
  if (applied != 0) {
    *applied = pwm;
  }
}

void hal_pwm_enable(void) {
  if (!hw_tripped) {
    gates_on = true;
    shorted = false;
  }
}

void hal_pwm_disable(void) {
  gates_on = false;
  shorted = false;
}

void hal_pwm_short(void) {
  if (!hw_tripped) {
    gates_on = false;
    shorted = true;
  }
}

bool hal_pwm_is_shorted(void) {
  return shorted;
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

uint32_t hal_fault_hw_source(void) {
  return (in_flags & ISR_IN_GATE_DRIVER) != 0u ? (uint32_t)HAL_BREAK_GATE_DRIVER : 0u;
}

void hal_fault_hw_clear(void) {
  hw_tripped = false;
  in_flags &= ~ISR_IN_GATE_DRIVER;
}

void hal_watchdog_kick(void) {}

bool hal_reset_by_watchdog(void) {
  return false;
}

void hal_isr_stats(hal_isr_stats_t *st) {
  st->cycles_last = st->cycles_max = st->cycles_mean = st->overruns = 0u;
}

uint32_t hal_isr_overruns(void) {
  return 0u;
}
