/*
 * drive_overrun.h - the ISR overrun check: the board counts the periods
 * whose interrupt ended after the next carrier valley (hal_isr_overruns():
 * its compare values missed the timer's update, the previous pattern ran
 * one more period, the next interrupt was delayed). At the slow rate the
 * drive notes whether the count moved; overruns in overrun_k of the last
 * overrun_n slow periods trip the `overrun` fault (docs/faults.md). A
 * single late interrupt is ridden through.
 */
#ifndef FLUXDRIVE_DRIVE_OVERRUN_H
#define FLUXDRIVE_DRIVE_OVERRUN_H

#include <stdbool.h>
#include <stdint.h>

#include "drive.h"
#include "hal.h"

/* The board's count as it stands: earlier overruns are not this run's. */
void drive_overrun_init(drive_t *drv);
/* The window with this slow period's `any` (count moved) shifted in: true
 * when the fault is due. */
bool drive_overrun_window(drive_t *drv, uint32_t count);

/* Once per slow period (the ISR's slow path): true when the fault is due.
 * Inline, the usual case (no overrun now nor in the window) costs a read
 * and two compares. */
static inline bool drive_overrun_check(drive_t *drv) {
  const uint32_t count = hal_isr_overruns();
  if (count == drv->overrun_seen && drv->overrun_hist == 0u) {
    return false;
  }
  return drive_overrun_window(drv, count);
}

#endif
