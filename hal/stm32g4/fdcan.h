/* fdcan.h - FDCAN1 in classic CAN mode (RM0440 section 44). */
#ifndef FLUXDRIVE_STM32G4_FDCAN_H
#define FLUXDRIVE_STM32G4_FDCAN_H

#include <stdbool.h>
#include <stdint.h>

/* Nominal bit timing for f_kernel = 170 MHz (PCLK1), 17 time quanta per
 * bit: sync 1 + TSEG1 13 + TSEG2 3 (sample point 82.4 %), SJW 3.
 * Prescaler 10 -> 1 Mbit/s, 20 -> 500 kbit/s, 40 -> 250 kbit/s. */
typedef struct {
  uint32_t brp, tseg1, tseg2, sjw; /* in time quanta, not register values */
} fdcan_timing_t;

/* false for a bit rate that 170 MHz / 17 tq cannot produce exactly. */
bool hal_fdcan_timing(uint32_t bitrate, fdcan_timing_t *t);
/* Pins, clock, message RAM, timing, filters (node id), leave INIT.
 * false on an unsupported bit rate or an INIT time-out. */
bool hal_fdcan_init(uint32_t bitrate, uint32_t node_id, uint32_t mask);

#endif
