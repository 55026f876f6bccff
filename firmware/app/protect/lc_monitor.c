/*
 * protect/lc_monitor.c - the loss-of-control monitor (protect/lc_monitor.h).
 */
#include "protect/lc_monitor.h"

FD_COLD void protect_lc_configure(protect_lc_t *p, const protect_lc_cfg_t *c) {
  const float i_lim = c->lc_current * c->i_max;
  p->i_lim2 = i_lim * i_lim;
  p->torque_tol = c->lc_track * c->torque_scale;
  p->delta_lim = c->delta_max + c->lc_delta;
  p->track = c->lc_track;
  p->obs_tol = c->lc_track * c->flux_scale;
  p->n_fast = c->lc_time / c->ts;
  p->n_track = c->lc_track_time / c->ts;
}

FD_COLD void protect_lc_reset(protect_lc_t *p) {
  for (unsigned k = 0; k < DRIVE_LC_COUNT; ++k) {
    p->n[k] = 0u;
  }
  p->held = 0u;
}

uint32_t protect_lc_count(protect_lc_t *p, uint32_t cond) {
  /* a condition that does not hold restarts its count (a count at 0
   * never trips: lc_time, lc_track_time > 0 by their ranges) */
  uint32_t walk = (cond | p->held) & ((1u << DRIVE_LC_COUNT) - 1u);
  uint32_t trip = 0u;
  /* the set bits only, lowest first (a condition that holds alone, the
   * torque's at a torque step, is one pass, not three): DRIVE_LC_COUNT
   * passes at most */
  for (unsigned pass = 0; pass < DRIVE_LC_COUNT && walk != 0u; ++pass) {
    const unsigned k = (unsigned)__builtin_ctz(walk);
    const uint32_t bit = 1u << k;
    walk &= walk - 1u;
    p->n[k] = (cond & bit) != 0u ? p->n[k] + 1u : 0u;
    const float n_max = (bit & PROTECT_LC_FAST) != 0u ? p->n_fast : p->n_track;
    if ((float)p->n[k] >= n_max) {
      trip |= bit;
    }
  }
  p->held = cond;
  return trip;
}
