/*
 * profile.c - evaluation and validation of time profiles (profile.h).
 */
#include "profile.h"

#include <math.h>
#include <stddef.h>

#define PROFILE_TWO_PI 6.283185307179586476925

static double term_eval(const profile_term_t *k, double t) {
  switch (k->kind) {
  case PROFILE_CONST:
    return k->value;
  case PROFILE_STEP:
    return t >= k->t0 ? k->value : 0.0;
  case PROFILE_RAMP:
    if (t <= k->t0) {
      return 0.0;
    }
    if (t >= k->t1) {
      return k->value;
    }
    return k->value * (t - k->t0) / (k->t1 - k->t0);
  case PROFILE_SINE:
    if (t < k->t0 || (k->t1 > k->t0 && t > k->t1)) {
      return 0.0;
    }
    return k->value * sin(PROFILE_TWO_PI * k->freq * (t - k->t0) + k->phase);
  }
  return 0.0;
}

double profile_eval(const profile_t *p, double t) {
  double y = 0.0;
  for (int i = 0; i < p->n; i++) {
    y += term_eval(&p->term[i], t);
  }
  return y;
}

/* End of the interval from t over which term k keeps its value at t. */
static double term_span(const profile_term_t *k, double t) {
  switch (k->kind) {
  case PROFILE_CONST:
    return INFINITY;
  case PROFILE_STEP:
    return t >= k->t0 ? INFINITY : k->t0;
  case PROFILE_RAMP:
    if (t >= k->t1) {
      return INFINITY;
    }
    return t < k->t0 ? k->t0 : t; /* 0 up to t0 (inclusive), then rising */
  case PROFILE_SINE:
    if (k->t1 > k->t0 && t > k->t1) {
      return INFINITY;
    }
    return t < k->t0 ? k->t0 : t;
  }
  return t;
}

double profile_eval_span(const profile_t *p, double t, double *t_end) {
  double end = INFINITY;
  for (int i = 0; i < p->n; i++) {
    const double e = term_span(&p->term[i], t);
    end = e < end ? e : end;
  }
  *t_end = end;
  return profile_eval(p, t);
}

void profile_bounds(const profile_t *p, double *lo, double *hi) {
  double l = 0.0, h = 0.0;
  for (int i = 0; i < p->n; i++) {
    const profile_term_t *k = &p->term[i];
    const double v = k->kind == PROFILE_SINE ? fabs(k->value) : k->value;
    if (k->kind == PROFILE_CONST) {
      l += v;
      h += v;
    } else if (k->kind == PROFILE_SINE) {
      l -= v;
      h += v;
    } else { /* step, ramp: between 0 and the value */
      l += v < 0.0 ? v : 0.0;
      h += v > 0.0 ? v : 0.0;
    }
  }
  *lo = l;
  *hi = h;
}

int profile_add(profile_t *p, profile_term_t term) {
  if (p->n < 0 || p->n >= PROFILE_MAX_TERMS) {
    return -1;
  }
  p->term[p->n++] = term;
  return 0;
}

int profile_check(const profile_t *p, const char **field) {
  const char *bad = NULL;
  if (p->n < 0 || p->n > PROFILE_MAX_TERMS) {
    bad = "n";
  }
  for (int i = 0; bad == NULL && i < p->n; i++) {
    const profile_term_t *k = &p->term[i];
    if (k->kind != PROFILE_CONST && k->kind != PROFILE_STEP && k->kind != PROFILE_RAMP &&
        k->kind != PROFILE_SINE) {
      bad = "term.kind";
    } else if (!isfinite(k->value)) {
      bad = "term.value";
    } else if (!isfinite(k->t0)) {
      bad = "term.t0";
    } else if (!isfinite(k->t1) || (k->kind == PROFILE_RAMP && !(k->t1 > k->t0))) {
      bad = "term.t1"; /* a ramp needs t1 > t0 (its slope divides by t1 - t0) */
    } else if (k->kind == PROFILE_SINE && !(isfinite(k->freq) && k->freq >= 0.0)) {
      bad = "term.freq";
    } else if (!isfinite(k->phase)) {
      bad = "term.phase";
    }
  }
  if (bad != NULL) {
    if (field != NULL) {
      *field = bad;
    }
    return -1;
  }
  return 0;
}
