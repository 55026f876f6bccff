/*
 * proc_offset.c - offset calibration as a procedure (proc.h): with the gates
 * off, offset_samples raw current samples averaged per phase; an offset
 * beyond offset_max is the `offset` fault. The offsets go into the drive's
 * (su->offset) when found: phase by phase, up to the first refused.
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"

FD_COLD static void offset_init(proc_state_t *st, const proc_setup_t *su) {
  (void)su;
  proc_offset_t *o = &st->offset;
  o->acc[0] = o->acc[1] = o->acc[2] = 0.0f;
  o->n = 0u;
}

FD_COLD static int offset_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                               proc_out_t *out) {
  proc_offset_t *o = &st->offset;
  *out = (proc_out_t){{0.0f, 0.0f}, false, false, 0u};
  for (int x = 0; x < 3; ++x) {
    o->acc[x] += in->s->i_abc[x];
  }
  o->n++;
  if (o->n < su->cfg->offset_samples) {
    return PROC_RUNNING;
  }
  const float n = (float)o->n;
  for (int x = 0; x < 3; ++x) {
    su->offset[x] = o->acc[x] / n;
    if (fabsf(su->offset[x]) > su->cfg->offset_max) {
      out->fault = DRIVE_FAULT_OFFSET;
      return PROC_FAILED;
    }
  }
  return PROC_DONE;
}

FD_COLD static void offset_publish(const proc_state_t *st, proc_telemetry_t *tm) {
  const proc_offset_t *o = &st->offset;
  tm->phase = 0u;
  tm->n = o->n;
  /* the averages so far: the offsets once done */
  const float k = o->n > 0u ? 1.0f / (float)o->n : 0.0f;
  for (int x = 0; x < 3; ++x) {
    tm->result[x] = o->acc[x] * k;
  }
}

const proc_row_t proc_offset = {
    .name = "offset",
    .id = PROC_OFFSET,
    .state = DRIVE_STATE_OFFSET_CAL,
    .caps = PROC_CAP_IDENT,
    .check = NULL,
    .wanted = NULL,
    .init = offset_init,
    .step = offset_step,
    .abort = NULL,
    .publish = offset_publish,
};
