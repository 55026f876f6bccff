/*
 * log_columns.h - the SIL log's columns, from the signal tables (signal_row.h):
 * the SIL's own (sil_signal_table.h: plant, HAL), the drive's
 * (drive_signal_table.h), then the laws' and the position sources' signals
 * (their rows' hooks), each name once, in table order. A law's or a
 * source's column holds its getter's value while it is in force, 0
 * otherwise. Also `fluxdrive-sil --print-signals` (signals_json).
 */
#ifndef FD_SIL_LOG_COLUMNS_H
#define FD_SIL_LOG_COLUMNS_H

#include "drive_signals.h"
#include "sil_run.h"

#define LOG_COLUMNS_MAX 128
#define LOG_HOOK_MAX    32 /* signals of one law or one source */

typedef enum { LOG_COL_SIL = 0, LOG_COL_DRIVE, LOG_COL_LAW, LOG_COL_POS } log_col_kind_t;

typedef struct {
  const signal_row_t *row; /* the first row of that name (units, doc) */
  log_col_kind_t kind;
} log_column_t;

typedef struct {
  unsigned n;
  log_column_t col[LOG_COLUMNS_MAX];
  /* the column of signal i of law l / of source s */
  uint8_t law_col[DRIVE_LAW_COUNT][LOG_HOOK_MAX];
  uint8_t pos_col[POS_SOURCE_COUNT][LOG_HOOK_MAX];
} log_columns_t;

/* Builds the columns. 0, or -1 with the reason in err (too many, or a
 * name that two tables of different kinds both define). */
int log_columns_init(log_columns_t *c, char *err, size_t err_len);
/* One row: every column's value after ISR k. */
void log_columns_fill(const log_columns_t *c, const sil_step_t *st, double *row);
/* The SIL's own rows (sil_signal_table.h); *n rows. */
const signal_row_t *sil_signals(unsigned *n);
/* Where SIL row i comes from: "plant", "HAL" or "" (time). */
const char *sil_signal_source(unsigned i);

#endif
