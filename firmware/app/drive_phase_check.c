/*
 * drive_phase_check.c - phase balance on the telemetry copy (main loop);
 * drive_phase_check.h says what and why.
 */
#include "drive_phase_check.h"

#include <math.h>
#include <string.h>

#include "drive.h"
#include "math/fd_math.h"
#include "math/frames.h"

static void window_clear(drive_phase_check_t *p) {
  memset(p->abs, 0, sizeof p->abs);
  p->angle = 0.0f;
  p->n = 0;
}

/* 1 unbalanced, 0 balanced, -1 not judged. */
static int verdict(const drive_phase_check_t *p, float i_max) {
  const float big = fd_maxf(p->abs[0], fd_maxf(p->abs[1], p->abs[2]));
  if (p->n < DRIVE_PH_MIN_N || !(big > DRIVE_PH_FLOOR * i_max * (float)p->n)) {
    return -1;
  }
  for (int x = 0; x < 3; ++x) {
    if (p->abs[x] < DRIVE_PH_OPEN * big) {
      return 1;
    }
  }
  return 0;
}

void drive_phase_check(drive_t *drv) {
  drive_phase_check_t *p = &drv->host.ph;
  const drive_telemetry_t *tm = &drv->host.tm;
  const drive_config_t *c = &drv->creq.cfg;
  if (tm->isr_count == p->isr_last) {
    return; /* no fresh copy */
  }
  const uint32_t isrs = tm->isr_count - p->isr_last;
  const bool first = p->isr_last == 0u;
  p->isr_last = tm->isr_count;
  if (tm->state != DRIVE_STATE_RUN || first) {
    window_clear(p);
    p->bad = 0;
    return;
  }
  for (int x = 0; x < 3; ++x) {
    p->abs[x] += fabsf(tm->i_abc[x]);
  }
  p->n++;
  p->angle += fabsf(tm->omega_m) * c->pole_pairs * (float)isrs * c->ts;
  if (p->angle < FRAMES_2PI) {
    if (p->n >= DRIVE_PH_MAX_N) { /* too slow: no verdict */
      window_clear(p);
      p->bad = 0;
    }
    return;
  }
  const int v = verdict(p, c->i_max);
  p->bad = v > 0 ? p->bad + 1 : 0;
  window_clear(p);
  if (p->bad >= DRIVE_PH_TRIP) {
    p->bad = 0;
    p->trips++;
    drive_request_fault(drv, DRIVE_FAULT_LOST_CONTROL);
  }
}
