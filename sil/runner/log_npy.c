/*
 * log_npy.c - .npy structured-array log (see log_npy.h); its columns come
 * from the signal tables (log_columns.h).
 */
#include "log_npy.h"

#include <string.h>

enum { HEADER_LEN = 8192 };

static int write_header(log_npy_t *lg) {
  char dict[HEADER_LEN];
  int n = snprintf(dict, sizeof dict, "{'descr': [");
  for (unsigned i = 0u; i < lg->cols.n; ++i) {
    n += snprintf(dict + n, sizeof dict - (size_t)n, "('%s', '<f8'), ", lg->cols.col[i].row->name);
  }
  n += snprintf(dict + n, sizeof dict - (size_t)n,
                "], 'fortran_order': False, 'shape': (%20llu,), }", (unsigned long long)lg->rows);
  /* magic(6) + version(2) + len(2) + dict, padded with spaces, ends in \n,
   * total a multiple of 64 (format 1.0). */
  size_t total = 10 + (size_t)n + 1;
  size_t padded = (total + 63) / 64 * 64;
  memset(dict + n, ' ', padded - total);
  dict[padded - 10 - 1] = '\n';
  unsigned short hlen = (unsigned short)(padded - 10);
  unsigned char pre[10] = {0x93,
                           'N',
                           'U',
                           'M',
                           'P',
                           'Y',
                           1,
                           0,
                           (unsigned char)(hlen & 0xff),
                           (unsigned char)(hlen >> 8)};
  if (fseek(lg->f, 0, SEEK_SET) != 0 || fwrite(pre, 1, 10, lg->f) != 10 ||
      fwrite(dict, 1, hlen, lg->f) != hlen) {
    return -1;
  }
  return 0;
}

int log_npy_open(log_npy_t *lg, const char *path, int decimation) {
  memset(lg, 0, sizeof *lg);
  lg->decimation = decimation < 1 ? 1 : decimation;
  char err[128];
  if (log_columns_init(&lg->cols, err, sizeof err) != 0) {
    fprintf(stderr, "fluxdrive-sil: %s\n", err);
    return -1;
  }
  lg->f = fopen(path, "wb");
  if (lg->f == NULL) {
    return -1;
  }
  return write_header(lg);
}

void log_npy_observer(void *user, const sil_step_t *st) {
  log_npy_t *lg = user;
  if (lg->failed || st->k % (uint64_t)lg->decimation != 0) {
    return;
  }
  double row[LOG_COLUMNS_MAX];
  log_columns_fill(&lg->cols, st, row);
  /* x86-64 and Cortex hosts are little-endian, as '<f8' says. */
  if (fwrite(row, sizeof row[0], lg->cols.n, lg->f) != lg->cols.n) {
    lg->failed = 1;
    return;
  }
  lg->rows++;
}

int log_npy_close(log_npy_t *lg) {
  int r = lg->failed ? -1 : write_header(lg);
  if (fclose(lg->f) != 0) {
    r = -1;
  }
  lg->f = NULL;
  return r;
}
