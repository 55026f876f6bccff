/*
 * signal_row.h - one row of a signal table: what the drive, a law or a
 * position source exposes for logs, CAN telemetry and docs.
 *
 * The tables: drive_signal_table.h (the drive's telemetry and state),
 * the laws' (ctrl_law_t.signals) and the position sources'
 * (pos_source_row_t.signals), and the SIL's own plant and HAL columns
 * (sil/runner/sil_signal_table.h). `fluxdrive-sil --print-signals` prints
 * them; `fluxdrive signals --write` renders docs/log-format.md, the DBC's
 * telemetry comments and the tools' table (tools/src/fluxdrive/signals.py);
 * the CTest test signals/agreement fails when one of them differs.
 *
 * Getters run in the main loop or the SIL's observer, never in the ISR:
 * they read what the ISR left and cost it nothing.
 */
#ifndef FLUXDRIVE_SIGNAL_ROW_H
#define FLUXDRIVE_SIGNAL_ROW_H

typedef enum {
  SIGNAL_F32 = 0, /* a physical value */
  SIGNAL_U32,     /* an integer: a count, an enum or bits */
  SIGNAL_BOOL     /* 0 or 1 */
} signal_type_t;

typedef struct {
  const char *name; /* the log column (docs/log-format.md) */
  signal_type_t type;
  const char *unit;
  const char *doc;
  /* the value from its owner: the drive's signal source
   * (drive_signal_src_t), the law's state (ctrl_state_t) or the source's
   * (pos_state_t); double: the log's precision, and angles the getter
   * computes (atan2) keep it */
  double (*get)(const void *owner);
} signal_row_t;

#endif
