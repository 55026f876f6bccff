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
  /* what the law estimated (loss-of-control monitor inputs) */
  double *iamp_meas, *delta_est, *torque_est, *torque_ref, *flux_est, *flux_ref, *obs_err;
  double *flux, *delta, *theta_err; /* true flux amplitude, load angle, used - true angle */
  double *duty_max;                 /* largest duty of the pattern the HAL applies */
  double *pos_res;                  /* the position check's residual / tolerance (its last check) */
  unsigned *faults, *state, *gates, *lc_cause;
  unsigned *asc; /* active short circuit over [t_k, t_k+1) */
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
  tr->iamp_meas[k] = hypot(tm->i_dq[0], tm->i_dq[1]);
  tr->delta_est[k] = tm->law_tm.delta;
  tr->torque_est[k] = tm->torque_est;
  tr->torque_ref[k] = tm->torque_ref;
  tr->flux_est[k] = tm->law_tm.flux;
  tr->flux_ref[k] = tm->law_tm.flux_ref;
  tr->obs_err[k] = tm->law_tm.obs_err;
  tr->flux[k] = hypot(p->lambda_dq[0], p->lambda_dq[1]);
  tr->delta[k] = atan2(p->lambda_dq[1], p->lambda_dq[0]);
  tr->theta_err[k] = remainder(tm->theta_e - p->theta_e, 2.0 * 3.14159265358979323846);
  tr->lc_cause[k] = tm->lc_cause;
  tr->duty_max[k] = fmax(tm->duty[0], fmax(tm->duty[1], tm->duty[2]));
  tr->pos_res[k] = st->drive->pos_chk.res;
  tr->faults[k] = st->drive->faults;
  tr->state[k] = st->drive->state;
  tr->gates[k] = st->gates_on;
  tr->asc[k] = st->asc;
}

static inline void trace_alloc(trace_t *tr, size_t cap) {
  tr->n = 0;
  tr->cap = cap;
  double **d[] = {&tr->t,         &tr->iq,        &tr->id,        &tr->speed,      &tr->torque,
                  &tr->v_dc,      &tr->imax_abs,  &tr->speed_ref, &tr->v_dc_meas,  &tr->imax_meas,
                  &tr->speed_est, &tr->iamp_meas, &tr->delta_est, &tr->torque_est, &tr->torque_ref,
                  &tr->flux_est,  &tr->flux_ref,  &tr->obs_err,   &tr->flux,       &tr->delta,
                  &tr->theta_err, &tr->duty_max,  &tr->pos_res};
  for (size_t i = 0; i < sizeof d / sizeof d[0]; ++i) {
    *d[i] = calloc(cap, sizeof(double));
  }
  unsigned **u[] = {&tr->faults, &tr->state, &tr->gates, &tr->lc_cause, &tr->asc};
  for (size_t i = 0; i < sizeof u / sizeof u[0]; ++i) {
    *u[i] = calloc(cap, sizeof(unsigned));
  }
}

static inline void trace_free(trace_t *tr) {
  double *d[] = {tr->t,         tr->iq,        tr->id,        tr->speed,      tr->torque,
                 tr->v_dc,      tr->imax_abs,  tr->speed_ref, tr->v_dc_meas,  tr->imax_meas,
                 tr->speed_est, tr->iamp_meas, tr->delta_est, tr->torque_est, tr->torque_ref,
                 tr->flux_est,  tr->flux_ref,  tr->obs_err,   tr->flux,       tr->delta,
                 tr->theta_err, tr->duty_max,  tr->pos_res};
  for (size_t i = 0; i < sizeof d / sizeof d[0]; ++i) {
    free(d[i]);
  }
  unsigned *u[] = {tr->faults, tr->state, tr->gates, tr->lc_cause, tr->asc};
  for (size_t i = 0; i < sizeof u / sizeof u[0]; ++i) {
    free(u[i]);
  }
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

/* Largest, smallest and mean of x over the indices [k0, k1) (-inf, +inf,
 * NaN when empty). */
static inline double trace_max(const double *x, size_t k0, size_t k1) {
  double m = -INFINITY;
  for (size_t k = k0; k < k1; ++k) {
    m = fmax(m, x[k]);
  }
  return m;
}

static inline double trace_min(const double *x, size_t k0, size_t k1) {
  double m = INFINITY;
  for (size_t k = k0; k < k1; ++k) {
    m = fmin(m, x[k]);
  }
  return m;
}

static inline double trace_mean(const double *x, size_t k0, size_t k1) {
  double s = 0.0;
  for (size_t k = k0; k < k1; ++k) {
    s += x[k];
  }
  return k1 > k0 ? s / (double)(k1 - k0) : NAN;
}

#endif
