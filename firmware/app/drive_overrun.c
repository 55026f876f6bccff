/*
 * drive_overrun.c - the ISR overrun check (see drive_overrun.h).
 */
#include "drive_overrun.h"

void drive_overrun_init(drive_t *drv) {
  drv->overrun_seen = hal_isr_overruns();
  drv->overrun_hist = 0u;
}

bool drive_overrun_window(drive_t *drv, uint32_t count) {
  const uint32_t any = count != drv->overrun_seen ? 1u : 0u;
  drv->overrun_seen = count;
  const uint32_t n = drv->cfg.overrun_n; /* 1..32 (parameter range) */
  const uint32_t mask = n >= 32u ? 0xFFFFFFFFu : (1u << n) - 1u;
  uint32_t h = ((drv->overrun_hist << 1) | any) & mask;
  drv->overrun_hist = h;
  uint32_t set = 0u;
  for (int b = 0; b < 32 && h != 0u; ++b) { /* one pass per set bit */
    h &= h - 1u;
    set++;
  }
  return set >= drv->cfg.overrun_k;
}
