/*
 * sil_test_util.h - helpers for SIL scenario tests: run a scenario given
 * as JSON text and record the signals a test asserts on at every period.
 */
#ifndef SIL_TEST_UTIL_H
#define SIL_TEST_UTIL_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "scenario.h"
#include "sil_run.h"

typedef struct {
  size_t n, cap;
  double *t, *iq, *id, *speed, *torque, *v_dc, *imax_abs, *speed_ref;
  double *v_dc_meas, *imax_meas, *speed_est; /* what the ISR saw */
  unsigned *faults, *state, *gates;
} trace_t;

static inline void trace_observer(void *user, const sil_step_t *st) {
  trace_t *tr = user;
  if (tr->n >= tr->cap) {
    return;
  }
  size_t k = tr->n++;
  const plant_state_t *p = st->plant;
  tr->t[k] = st->t;
  tr->id[k] = p->i_dq[0];
  tr->iq[k] = p->i_dq[1];
  tr->speed[k] = p->omega_m;
  tr->torque[k] = p->torque;
  tr->v_dc[k] = p->v_dc;
  tr->imax_abs[k] = fmax(fabs(p->i_abc[0]), fmax(fabs(p->i_abc[1]), fabs(p->i_abc[2])));
  /* lock-step: the ISR's own telemetry (not the main loop's copy) */
  const drive_telemetry_t *tm = &st->drive->tm;
  tr->speed_ref[k] = tm->speed_ref;
  tr->v_dc_meas[k] = st->adc->v_dc;
  tr->imax_meas[k] = fmax(fabs(tm->i_abc[0]), fmax(fabs(tm->i_abc[1]), fabs(tm->i_abc[2])));
  tr->speed_est[k] = tm->omega_m;
  tr->faults[k] = st->drive->faults;
  tr->state[k] = st->drive->state;
  tr->gates[k] = st->gates_on;
}

static inline void trace_alloc(trace_t *tr, size_t cap) {
  tr->n = 0;
  tr->cap = cap;
  double **d[] = {&tr->t,         &tr->iq,        &tr->id,       &tr->speed,
                  &tr->torque,    &tr->v_dc,      &tr->imax_abs, &tr->speed_ref,
                  &tr->v_dc_meas, &tr->imax_meas, &tr->speed_est};
  for (size_t i = 0; i < sizeof d / sizeof d[0]; ++i) {
    *d[i] = calloc(cap, sizeof(double));
  }
  tr->faults = calloc(cap, sizeof(unsigned));
  tr->state = calloc(cap, sizeof(unsigned));
  tr->gates = calloc(cap, sizeof(unsigned));
}

static inline void trace_free(trace_t *tr) {
  double *d[] = {tr->t,        tr->iq,        tr->id,        tr->speed,     tr->torque,   tr->v_dc,
                 tr->imax_abs, tr->speed_ref, tr->v_dc_meas, tr->imax_meas, tr->speed_est};
  for (size_t i = 0; i < sizeof d / sizeof d[0]; ++i) {
    free(d[i]);
  }
  free(tr->faults);
  free(tr->state);
  free(tr->gates);
}

/* Parses and runs; fails the test on any error. */
static inline void run_json(const char *json, scenario_t *sc, trace_t *tr, sil_result_t *res) {
  char err[512];
  int r = scenario_parse(json, "test", sc, err, sizeof err);
  if (r != 0) {
    fprintf(stderr, "%s\n", err);
  }
  assert_int_equal(r, 0);
  trace_alloc(tr, (size_t)(sc->duration / sc->plant.ts) + 2);
  r = sil_run(sc, trace_observer, tr, res, err, sizeof err);
  if (r != 0) {
    fprintf(stderr, "%s\n", err);
  }
  assert_int_equal(r, 0);
}

/* First index where x[k] > thr (n when never). */
static inline size_t first_above(const double *x, size_t n, double thr) {
  size_t k = 0;
  while (k < n && !(x[k] > thr)) {
    ++k;
  }
  return k;
}

/* First index with a fault (n when never). */
static inline size_t first_fault(const trace_t *tr) {
  size_t k = 0;
  while (k < tr->n && tr->faults[k] == 0u) {
    ++k;
  }
  return k;
}

/* First index at or after `from` where t >= t0. */
static inline size_t idx_at(const trace_t *tr, double t0) {
  size_t k = 0;
  while (k < tr->n && tr->t[k] < t0) {
    ++k;
  }
  return k;
}

#endif
