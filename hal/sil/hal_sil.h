/*
 * hal_sil.h - the SIL implementation of hal.h. The runner owns a
 * hal_sil_t, binds it, fills `sample` from the plant before each ISR and
 * reads back the duties and the gate state after it. CAN frames pass
 * through two bounded queues (the transport of the CAN issue feeds them).
 */
#ifndef FLUXDRIVE_HAL_SIL_H
#define FLUXDRIVE_HAL_SIL_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"

#define HAL_SIL_CAN_QUEUE 256

typedef struct {
  hal_can_frame_t frame[HAL_SIL_CAN_QUEUE];
  uint32_t head, tail; /* head - tail frames pending */
  uint32_t dropped;
} hal_sil_can_queue_t;

typedef struct {
  hal_adc_sample_t sample; /* what hal_adc_read returns */
  float duty[3];           /* preloaded duties (act from the next period) */
  bool gates_on;
  bool hw_tripped; /* break input latch (set by the runner) */
  uint32_t time_us;
  uint32_t watchdog_kicks;
  hal_sil_can_queue_t can_rx; /* towards the firmware */
  hal_sil_can_queue_t can_tx; /* from the firmware */
} hal_sil_t;

void hal_sil_init(hal_sil_t *h);
/* All hal_* calls act on the bound context (one drive per process). */
void hal_sil_bind(hal_sil_t *h);

bool hal_sil_can_push(hal_sil_can_queue_t *q, const hal_can_frame_t *f);
bool hal_sil_can_pop(hal_sil_can_queue_t *q, hal_can_frame_t *f);

#endif
