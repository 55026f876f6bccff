/*
 * protect/isum.h - the current-sum (current-sensor) check, an owned part
 * of the drive's protections (docs/architecture.md, "Adding a protection").
 *
 * The three measured phase currents sum to zero (Kirchhoff, star
 * connection): a gain error, an offset drift or a lost channel shows as a
 * sum beyond i_sum_rel of the largest current (and the noise floor
 * i_sum_abs). Checked at the slow rate (the drive's schedule table) with a
 * leaky count (a single channel's error vanishes where its current crosses
 * zero): the fault after PROTECT_ISUM_TRIP more slow periods over than
 * under. Only where the board measures all three (HAL_CAP_I_ABC) and the
 * gates are on; otherwise the count restarts.
 */
#ifndef FLUXDRIVE_PROTECT_ISUM_H
#define FLUXDRIVE_PROTECT_ISUM_H

#include <stdbool.h>
#include <stdint.h>

#define PROTECT_ISUM_TRIP 8

typedef struct {
  int32_t n; /* the leaky count */
} protect_isum_t;

/* What the check reads (filled by drive.c). */
typedef struct {
  const float *i_abc; /* the last period's offset-corrected currents [A] */
  float i_sum_abs;    /* noise floor [A] */
  float i_sum_rel;    /* of the largest current */
  bool active;        /* all three measured, gates on */
} protect_isum_view_t;

/* One slow period: DRIVE_FAULT_CURRENT_SENSOR when it trips, else 0. */
uint32_t protect_isum_step(protect_isum_t *p, const protect_isum_view_t *v);

#endif
