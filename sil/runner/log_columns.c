/*
 * log_columns.c - the SIL log's columns from the signal tables (see
 * log_columns.h).
 */
#include "log_columns.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ctrl_laws.h"
#include "sil_signal_table.h"

/* the true stator-flux-frame currents: projection of i on lambda_s (k 0)
 * and its quadrature (k 1) (Rubino 2020, the (ds, qs) frame) */
static double sil_sig_i_fs(const plant_state_t *p, int k) {
  const double ld = p->lambda_dq[0], lq = p->lambda_dq[1];
  const double flux = hypot(ld, lq);
  if (!(flux > 0.0)) {
    return 0.0;
  }
  return k == 0 ? (ld * p->i_dq[0] + lq * p->i_dq[1]) / flux
                : (ld * p->i_dq[1] - lq * p->i_dq[0]) / flux;
}

#define SIL_SIG_GETTER(name, type, unit, source, value, doc)                                       \
  static double sil_sig_##name(const void *owner) {                                                \
    const sil_step_t *st = owner;                                                                  \
    const plant_state_t *p = st->plant;                                                            \
    (void)p;                                                                                       \
    return (double)(value);                                                                        \
  }
SIL_SIGNAL_TABLE(SIL_SIG_GETTER)
#undef SIL_SIG_GETTER

#define SIL_SIG_ROW(name, type, unit, source, value, doc)                                          \
  {#name, SIGNAL_##type, unit, doc, sil_sig_##name},
static const signal_row_t sil_rows[] = {SIL_SIGNAL_TABLE(SIL_SIG_ROW)};
#undef SIL_SIG_ROW
#define SIL_SIG_SOURCE(name, type, unit, source, value, doc) source,
static const char *const sil_sources[] = {SIL_SIGNAL_TABLE(SIL_SIG_SOURCE)};
#undef SIL_SIG_SOURCE

const signal_row_t *sil_signals(unsigned *n) {
  *n = (unsigned)(sizeof sil_rows / sizeof sil_rows[0]);
  return sil_rows;
}

const char *sil_signal_source(unsigned i) {
  return i < sizeof sil_sources / sizeof sil_sources[0] ? sil_sources[i] : "";
}

/* The column of that name, or a new one; -1 when full or when the name is
 * another kind's. */
static int column(log_columns_t *c, const signal_row_t *row, log_col_kind_t kind, char *err,
                  size_t err_len) {
  for (unsigned i = 0u; i < c->n; ++i) {
    if (strcmp(c->col[i].row->name, row->name) == 0) {
      if (c->col[i].kind != kind) {
        snprintf(err, err_len, "log column '%s' is defined by two signal tables", row->name);
        return -1;
      }
      return (int)i;
    }
  }
  if (c->n >= LOG_COLUMNS_MAX) {
    snprintf(err, err_len, "more than %d log columns", LOG_COLUMNS_MAX);
    return -1;
  }
  c->col[c->n] = (log_column_t){row, kind};
  return (int)c->n++;
}

/* A hook's signals (a law's or a source's) into columns: their map. */
static int hook(log_columns_t *c, const signal_row_t *sig, unsigned n, log_col_kind_t kind,
                uint8_t map[LOG_HOOK_MAX], char *err, size_t err_len) {
  if (n > LOG_HOOK_MAX) {
    snprintf(err, err_len, "more than %d signals in one law or source", LOG_HOOK_MAX);
    return -1;
  }
  for (unsigned i = 0u; i < n; ++i) {
    const int k = column(c, &sig[i], kind, err, err_len);
    if (k < 0) {
      return -1;
    }
    map[i] = (uint8_t)k;
  }
  return 0;
}

int log_columns_init(log_columns_t *c, char *err, size_t err_len) {
  memset(c, 0, sizeof *c);
  unsigned n;
  const signal_row_t *s = sil_signals(&n);
  for (unsigned i = 0u; i < n; ++i) {
    if (column(c, &s[i], LOG_COL_SIL, err, err_len) < 0) {
      return -1;
    }
  }
  const drive_signal_t *d = drive_signals(&n);
  for (unsigned i = 0u; i < n; ++i) {
    if (column(c, &d[i].row, LOG_COL_DRIVE, err, err_len) < 0) {
      return -1;
    }
  }
  for (unsigned l = 0u; l < (unsigned)DRIVE_LAW_COUNT; ++l) {
    const ctrl_law_t *law = ctrl_law((drive_law_t)l);
    if (hook(c, law->signals, law->n_signals, LOG_COL_LAW, c->law_col[l], err, err_len) != 0) {
      return -1;
    }
  }
  for (unsigned p = 0u; p < (unsigned)POS_SOURCE_COUNT; ++p) {
    const pos_source_row_t *src = pos_source((pos_source_t)p);
    if (hook(c, src->signals, src->n_signals, LOG_COL_POS, c->pos_col[p], err, err_len) != 0) {
      return -1;
    }
  }
  return 0;
}

void log_columns_fill(const log_columns_t *c, const sil_step_t *st, double *row) {
  const drive_t *drv = st->drive;
  /* lock-step: the ISR has returned; its own telemetry */
  const drive_signal_src_t src = {drv, &drv->tm};
  for (unsigned i = 0u; i < c->n; ++i) {
    const log_column_t *col = &c->col[i];
    switch (col->kind) {
    case LOG_COL_SIL:
      row[i] = col->row->get(st);
      break;
    case LOG_COL_DRIVE:
      row[i] = col->row->get(&src);
      break;
    case LOG_COL_LAW:
    case LOG_COL_POS:
    default:
      row[i] = 0.0; /* unless the law or source in force has it, below */
      break;
    }
  }
  /* the law whose state is initialised (ctrl_t.law) and its row */
  const ctrl_law_t *law = drv->ctrl.impl;
  if (law != NULL && (unsigned)drv->ctrl.law < (unsigned)DRIVE_LAW_COUNT) {
    for (unsigned i = 0u; i < law->n_signals; ++i) {
      row[c->law_col[drv->ctrl.law][i]] = law->signals[i].get(&drv->ctrl.st);
    }
  }
  const pos_source_row_t *ps = drv->pos_src;
  for (unsigned p = 0u; ps != NULL && p < (unsigned)POS_SOURCE_COUNT; ++p) {
    if (pos_source((pos_source_t)p) == ps) {
      for (unsigned i = 0u; i < ps->n_signals; ++i) {
        row[c->pos_col[p][i]] = ps->signals[i].get(&drv->pos_st);
      }
      break;
    }
  }
}
