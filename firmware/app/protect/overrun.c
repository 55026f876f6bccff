/*
 * protect/overrun.c - the ISR overrun check (protect/overrun.h).
 */
#include "protect/overrun.h"

#include "drive_enums.h"
#include "math/fd_math.h"

FD_COLD void protect_overrun_init(protect_overrun_t *p, uint32_t count) {
  p->seen = count;
  p->hist = 0u;
}

/* In flash (FD_COLD): only while overruns are in the window (the inline
 * step's usual case does not call it). */
FD_COLD uint32_t protect_overrun_window(protect_overrun_t *p, const protect_overrun_view_t *v) {
  const uint32_t any = v->count != p->seen ? 1u : 0u;
  p->seen = v->count;
  const uint32_t n = v->n; /* 1..32 (parameter range) */
  const uint32_t mask = n >= 32u ? 0xFFFFFFFFu : (1u << n) - 1u;
  uint32_t h = ((p->hist << 1) | any) & mask;
  p->hist = h;
  uint32_t set = 0u;
  for (int b = 0; b < 32 && h != 0u; ++b) { /* one pass per set bit */
    h &= h - 1u;
    set++;
  }
  return set >= v->k ? DRIVE_FAULT_OVERRUN : 0u;
}
