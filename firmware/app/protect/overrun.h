/*
 * protect/overrun.h - the ISR overrun check, an owned part of the drive's
 * protections (docs/architecture.md, "Adding a protection"): the board
 * counts the periods whose interrupt ended after the next carrier valley
 * (hal_isr_overruns(): its compare values missed the timer's update, the
 * previous pattern ran one more period, the next interrupt was delayed).
 * At the slow rate (the drive's schedule table) the part notes whether the
 * count moved; overruns in overrun_k of the last overrun_n slow periods
 * trip the `overrun` fault (docs/faults.md). A single late interrupt is
 * ridden through.
 */
#ifndef FLUXDRIVE_PROTECT_OVERRUN_H
#define FLUXDRIVE_PROTECT_OVERRUN_H

#include <stdint.h>

typedef struct {
  uint32_t seen; /* the board's overrun count at the last slow period */
  uint32_t hist; /* bit j: overruns in the slow period j back */
} protect_overrun_t;

/* What the check reads each slow period. */
typedef struct {
  uint32_t count; /* hal_isr_overruns() now */
  uint32_t n;     /* overrun_n: the window, 1..32 slow periods (parameter range) */
  uint32_t k;     /* overrun_k: overruns in the window that trip */
} protect_overrun_view_t;

/* The board's count as it stands: earlier overruns are not this run's. */
void protect_overrun_init(protect_overrun_t *p, uint32_t count);
/* The window with this slow period's `any` (count moved) shifted in:
 * DRIVE_FAULT_OVERRUN when the fault is due, else 0. */
uint32_t protect_overrun_window(protect_overrun_t *p, const protect_overrun_view_t *v);

/* Once per slow period: DRIVE_FAULT_OVERRUN when the fault is due, else 0.
 * Inline, the usual case (no overrun now nor in the window) costs two
 * compares. */
static inline uint32_t protect_overrun_step(protect_overrun_t *p, const protect_overrun_view_t *v) {
  if (v->count == p->seen && p->hist == 0u) {
    return 0u;
  }
  return protect_overrun_window(p, v);
}

#endif
