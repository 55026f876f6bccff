/*
 * hal_sil.h - the SIL implementation of hal.h. The runner owns a
 * hal_sil_t, binds it, fills `sample` from the plant before each ISR and
 * reads back the pattern and the gate state after it. The board it models
 * (duty range, timer resolution, watchdog) is set by the scenario
 * (docs/scenarios.md, "board"); CAN frames pass through two bounded queues
 * (the transports feed them).
 *
 * The plant samples currents, DC link and encoder at the carrier valley:
 * t_i = t_enc = 0 (hal_caps_t), and one star-point sample at the valley.
 */
#ifndef FLUXDRIVE_HAL_SIL_H
#define FLUXDRIVE_HAL_SIL_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"
#include "hal_pattern.h"

#define HAL_SIL_CAN_QUEUE 256

typedef struct {
  hal_can_frame_t frame[HAL_SIL_CAN_QUEUE];
  uint32_t head, tail; /* head - tail frames pending */
  uint32_t dropped;
} hal_sil_can_queue_t;

/* The board the SIL models. */
typedef struct {
  float duty_min, duty_max;         /* hal_caps_t */
  uint32_t timer_counts;            /* compare steps per period (ARR); 0: exact duties */
  float dead_time;                  /* [s] */
  float ts;                         /* [s] */
  uint32_t watchdog_ms;             /* watchdog timeout; 0: none */
  bool asym_edges;                  /* HAL_CAP_ASYM_EDGES */
  float i_full_scale, v_full_scale; /* the ADC ranges (hal_caps_t; 0: not known) */
  float i_lsb;                      /* the current ADC's step (hal_caps_t; 0: not known) */
} hal_sil_board_t;

typedef struct {
  hal_caps_t caps;
  uint32_t timer_counts;
  hal_pattern_t timer;      /* the timer model of caps and timer_counts (hal_pattern.h) */
  hal_sample_t sample;      /* what hal_adc_read returns */
  hal_pwm_t pwm;            /* preloaded pattern (acts from the next period) */
  uint32_t pwm_clamped;     /* writes with a leg outside the duty range (caps): the
                             * drive asked for what the board cannot do */
  float clamp_lo, clamp_hi; /* caps.duty_min - tol, caps.duty_max + tol (hal_pwm_write) */
  bool gates_on;            /* modulating (the preloaded pattern) */
  bool asc;                 /* active short circuit: all low sides on (hal_pwm_short) */
  bool hw_tripped;          /* break input latch (set by the runner) */
  uint32_t hw_source;       /* which break input latched (HAL_BREAK_*; 0: the comparator) */
  uint32_t time_us;
  /* watchdog: the runner calls hal_sil_watchdog_expired() every period */
  uint32_t watchdog_timeout_us;
  uint32_t watchdog_last_us;
  uint32_t watchdog_kicks;
  bool reset_by_watchdog;     /* what hal_reset_by_watchdog() reports */
  uint32_t isr_overruns;      /* interrupts that ended after the next valley
                               * (set by the runner: inject.isr_overrun) */
  hal_sil_can_queue_t can_rx; /* towards the firmware */
  hal_sil_can_queue_t can_tx; /* from the firmware */
} hal_sil_t;

void hal_sil_init(hal_sil_t *h, const hal_sil_board_t *board);
/* All hal_* calls act on the bound context (one drive per process). */
void hal_sil_bind(hal_sil_t *h);
/* True when the watchdog was not refreshed for its timeout at time now_us
 * (the runner then resets the MCU: gates off, drive_init). */
bool hal_sil_watchdog_expired(const hal_sil_t *h, uint32_t now_us);

bool hal_sil_can_push(hal_sil_can_queue_t *q, const hal_can_frame_t *f);
bool hal_sil_can_pop(hal_sil_can_queue_t *q, hal_can_frame_t *f);

#endif
