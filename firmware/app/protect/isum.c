/*
 * protect/isum.c - the current-sum check (protect/isum.h).
 */
#include "protect/isum.h"

#include <math.h>

#include "drive_enums.h"
#include "math/fd_math.h"

/* In flash (FD_COLD): once per slow period, as protect_ra_step. */
FD_COLD uint32_t protect_isum_step(protect_isum_t *p, const protect_isum_view_t *v) {
  if (!v->active) {
    p->n = 0;
    return 0u;
  }
  const float *i = v->i_abc;
  const float big = fd_maxf(fabsf(i[0]), fd_maxf(fabsf(i[1]), fabsf(i[2])));
  if (fabsf(i[0] + i[1] + i[2]) > fd_maxf(v->i_sum_abs, v->i_sum_rel * big)) {
    /* mut: current_sum_never_trips */
    if (++p->n >= PROTECT_ISUM_TRIP) {
      return DRIVE_FAULT_CURRENT_SENSOR;
    }
  } else if (p->n > 0) {
    p->n--;
  }
  return 0u;
}
