/*
 * protect/runaway.c - the run-away check (protect/runaway.h).
 */
#include "protect/runaway.h"

#include <math.h>

#include "math/fd_math.h"
#include "protect/lc_monitor.h"

FD_COLD void protect_ra_configure(protect_ra_t *p, float speed_max, float t_loop) {
  p->floor = PROTECT_RA_FLOOR * speed_max;
  const float nf = PROTECT_RA_TIME / t_loop + 0.5f; /* periods in the window, rounded */
  p->n_win = nf >= 2.0f ? (uint32_t)nf : 1u;
  p->q = p->n_win >= 4u ? p->n_win / 4u : 1u;
}

FD_COLD void protect_ra_reset(protect_ra_t *p) {
  p->n = 0u;
  p->w0 = 0.0f;
  p->w1 = 0.0f;
}

/* In flash (FD_COLD) with the other slow-rate parts: once per speed-loop
 * period, a few flops; the G474's CCM holds the every-period path and has
 * no room left for these with the DFC window (hal/stm32g4/stm32g474re.ld). */
FD_COLD uint32_t protect_ra_step(protect_ra_t *p, const protect_ra_view_t *v) {
  const float e = v->w - v->w_ref;
  const float ae = fabsf(e);
  if (!(ae > PROTECT_RA_MARGIN * fabsf(v->w_ref) + p->floor && v->torque * e < 0.0f)) {
    p->n = 0u;
    return 0u;
  }
  const uint32_t n_win = p->n_win, q = p->q;
  if (p->n == 0u) {
    p->w0 = 0.0f;
    p->w1 = 0.0f;
  }
  p->n++;
  if (p->n <= q) {
    p->w0 += v->w;
  }
  if (p->n + q > n_win) {
    p->w1 += v->w;
  }
  if (p->n >= n_win) {
    p->n = 0u; /* a new window */
    const float d = (p->w1 - p->w0) / (float)q;
    /* mut: runaway_no_growth_needed */
    const float away = e > 0.0f ? d : -d;
    /* mut: runaway_check_off */
    if (away > p->floor) {
      return DRIVE_LC_RUNAWAY;
    }
  }
  return 0u;
}
