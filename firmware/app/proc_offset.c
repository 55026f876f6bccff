/*
 * proc_offset.c - offset calibration as a procedure (proc.h): with the gates
 * off, offset_samples raw current samples averaged per phase; an offset
 * beyond offset_max is the `offset` fault. The offsets go into the drive's
 * (su->offset) when found: phase by phase, up to the first refused.
 *
 * The same samples give the sensors' noise: the sum of the three phase
 * currents is zero in a star winding (and at zero current), so its
 * spread over the window is the sensors' noise and quantisation alone.
 * PROC_OFFSET_NOISE_K (3) times its standard deviation becomes the
 * current-sum check's floor (su->i_sum_noise; protect/isum.h: the larger of
 * it and i_sum_abs): a board whose noise is above i_sum_abs would
 * otherwise trip `current_sensor` at low currents (a drawn machine's
 * small-signal levels did, issue 25).
 */
#include "proc.h"

#include <math.h>
#include <stddef.h>

#include "math/fd_math.h"

/* the floor: this many standard deviations. The check's leaky count trips
 * at 8 more samples over than under (protect/isum.h): at 3 sigma each is
 * over with p = 0.27 %, and noise alone never gets there */
#define PROC_OFFSET_NOISE_K 3.0f

FD_COLD static void offset_init(proc_state_t *st, const proc_setup_t *su) {
  (void)su;
  proc_offset_t *o = &st->offset;
  o->acc[0] = o->acc[1] = o->acc[2] = 0.0f;
  o->sum1 = o->sum2 = 0.0f;
  o->n = 0u;
}

/* The current sum's standard deviation over the samples so far [A]. */
FD_COLD static float offset_sum_sigma(const proc_offset_t *o) {
  if (o->n < 2u) {
    return 0.0f;
  }
  const float n = (float)o->n;
  const float m = o->sum1 / n;
  const float var = o->sum2 / n - m * m;
  return var > 0.0f && fd_isfinite(var) ? sqrtf(var) : 0.0f;
}

FD_COLD static int offset_step(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in,
                               proc_out_t *out) {
  proc_offset_t *o = &st->offset;
  *out = (proc_out_t){{0.0f, 0.0f}, false, false, 0u};
  for (int x = 0; x < 3; ++x) {
    o->acc[x] += in->s->i_abc[x];
  }
  const float sum = in->s->i_abc[0] + in->s->i_abc[1] + in->s->i_abc[2];
  o->sum1 += sum;
  o->sum2 += sum * sum;
  o->n++;
  if (o->n < su->cfg->offset_samples) {
    return PROC_RUNNING;
  }
  const float n = (float)o->n;
  /* mut: offset_noise_floor_zero */
  *su->i_sum_noise = PROC_OFFSET_NOISE_K * offset_sum_sigma(o);
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
  /* the current sum's noise (standard deviation) [A] */
  tm->result[3] = offset_sum_sigma(o);
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
