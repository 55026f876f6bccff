/*
 * profile.h - time profiles for references, load torque and imposed speed.
 * A profile is the sum of up to PROFILE_MAX_TERMS terms:
 *   const  value
 *   step   from t: +value           (0 before t)
 *   ramp   from t0 to t1: value*(t-t0)/(t1-t0), held at value after t1
 *   sine   from t0 (to t1 if t1 > t0): value*sin(2 pi freq (t-t0) + phase)
 * A profile with no terms is identically zero.
 */
#ifndef FD_PLANT_PROFILE_H
#define FD_PLANT_PROFILE_H

#define PROFILE_MAX_TERMS 16

typedef enum { PROFILE_CONST, PROFILE_STEP, PROFILE_RAMP, PROFILE_SINE } profile_kind_t;

typedef struct {
  profile_kind_t kind;
  double value; /* level, step height, ramp rise, or sine amplitude */
  double t0;    /* step time / ramp start / sine start [s] */
  double t1;    /* ramp end / sine end (ignored when <= t0) [s] */
  double freq;  /* sine frequency [Hz] */
  double phase; /* sine phase [rad] */
} profile_term_t;

typedef struct {
  int n;
  profile_term_t term[PROFILE_MAX_TERMS];
} profile_t;

double profile_eval(const profile_t *p, double t);
/* profile_eval(p, t), and in *t_end the end of the interval [t, *t_end)
 * (possibly empty: *t_end <= t) over which profile_eval() returns this same
 * value bit for bit (const terms, a step or sine before its start, a ramp
 * before its start or after its end, a sine after its end). Lets callers
 * that evaluate a profile many times per period skip the evaluation. */
double profile_eval_span(const profile_t *p, double t, double *t_end);
/* Bounds every value of the profile can take, from its terms alone (a
 * const term its value, a step or ramp between 0 and its value, a sine
 * +-its amplitude, summed): lo <= profile_eval(p, t) <= hi for every t.
 * No terms: 0, 0. */
void profile_bounds(const profile_t *p, double *lo, double *hi);
/* Appends a term; returns 0, or -1 when full. */
int profile_add(profile_t *p, profile_term_t term);
/* Validates term count, kinds and values (finite; ramp t1 > t0; sine
 * freq >= 0). Returns 0, or -1 and sets *field to the offending member
 * ("n", "term.kind", "term.value", "term.t0", "term.t1", "term.freq",
 * "term.phase"; static strings). */
int profile_check(const profile_t *p, const char **field);

#endif
