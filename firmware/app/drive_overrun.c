/*
 * drive_overrun.c - the ISR overrun check (see drive_overrun.h).
 */
#include "drive_overrun.h"

#include "hal.h"

void drive_overrun_init(drive_t *drv) {
  hal_isr_stats_t st;
  hal_isr_stats(&st);
  drv->overrun_seen = st.overruns;
  drv->overrun_hist = 0u;
}

bool drive_overrun_check(drive_t *drv) {
  hal_isr_stats_t st;
  hal_isr_stats(&st);
  const uint32_t any = st.overruns != drv->overrun_seen ? 1u : 0u;
  drv->overrun_seen = st.overruns;
  const uint32_t n = drv->cfg.overrun_n; /* 1..32 (parameter range) */
  const uint32_t mask = n >= 32u ? 0xFFFFFFFFu : (1u << n) - 1u;
  uint32_t h = ((drv->overrun_hist << 1) | any) & mask;
  drv->overrun_hist = h;
  uint32_t count = 0u;
  for (int b = 0; b < 32 && h != 0u; ++b) { /* one pass per set bit */
    h &= h - 1u;
    count++;
  }
  return count >= drv->cfg.overrun_k;
}
