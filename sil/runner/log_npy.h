/*
 * log_npy.h - the SIL log: a NumPy .npy file (format 1.0) holding a 1-D
 * structured array of little-endian float64 named fields, so that
 * np.load(path)['speed'] works directly. The columns are the signal
 * tables' (log_columns.h), listed in docs/log-format.md (generated).
 */
#ifndef FD_SIL_LOG_NPY_H
#define FD_SIL_LOG_NPY_H

#include <stdint.h>
#include <stdio.h>

#include "log_columns.h"
#include "sil_run.h"

typedef struct {
  FILE *f;
  uint64_t rows;
  int decimation;
  int failed;
  log_columns_t cols;
} log_npy_t;

/* Opens the file and writes a provisional header. Returns 0 or -1. */
int log_npy_open(log_npy_t *lg, const char *path, int decimation);
/* sil_run observer: appends one row every `decimation` periods. */
void log_npy_observer(void *user, const sil_step_t *st);
/* Patches the row count into the header and closes. Returns 0 or -1. */
int log_npy_close(log_npy_t *lg);

#endif
