/*
 * drive_signals.h - the drive's signal table (drive_signal_table.h) as
 * rows, and the lookup CAN uses.
 */
#ifndef FLUXDRIVE_DRIVE_SIGNALS_H
#define FLUXDRIVE_DRIVE_SIGNALS_H

#include "can_codec.h"
#include "drive.h"
#include "signal_row.h"

#define CAN_SIG_NONE CAN_SIG_COUNT

/* What a drive signal's getter reads: the telemetry its reader holds (the
 * main loop's consistent copy, drive_telemetry(); the lock-step SIL's the
 * ISR's own) and the drive. */
typedef struct {
  const drive_t *drv;
  const drive_telemetry_t *tm;
} drive_signal_src_t;

typedef struct {
  signal_row_t row; /* get(const drive_signal_src_t *) */
  can_sig_t can;    /* CAN_SIG_NONE: not on CAN */
  float can_scale;  /* CAN value = value * can_scale */
  const char *can_unit;
} drive_signal_t;

/* The table, in row order; *n rows. */
const drive_signal_t *drive_signals(unsigned *n);
/* The row a CAN signal carries (NULL: none). */
const drive_signal_t *drive_signal_of_can(can_sig_t c);

#endif
