/*
 * protect/lc_monitor.h - the loss-of-control monitor, an owned part of the
 * drive's protections (docs/architecture.md, "Adding a protection";
 * docs/faults.md). Every run period, on the law's output: each condition
 * (current, load angle, torque and flux tracking, observer against its
 * current model) must hold for its time, in periods without a break,
 * before the trip (lost_control, the conditions as lc_cause). The current
 * and the load angle within lc_time, the tracking ones within
 * lc_track_time.
 *
 * Inline: the ISR calls it every run period and its usual case (no
 * condition now, none held) is a few compares. A condition's count is
 * walked only while the condition holds or its count is not yet back to 0.
 */
#ifndef FLUXDRIVE_PROTECT_LC_MONITOR_H
#define FLUXDRIVE_PROTECT_LC_MONITOR_H

#include <math.h>
#include <stdint.h>

#include "math/fd_math.h"

/* Loss-of-control conditions (drive_telemetry_t.lc_cause). */
enum {
  DRIVE_LC_CURRENT = 1u << 0,  /* |i| above lc_current * i_max */
  DRIVE_LC_DELTA = 1u << 1,    /* |load angle| beyond delta_max + lc_delta */
  DRIVE_LC_TORQUE = 1u << 2,   /* torque off its (deliverable) reference */
  DRIVE_LC_FLUX = 1u << 3,     /* flux off its reference */
  DRIVE_LC_OBSERVER = 1u << 4, /* observer flux off the current model */
  DRIVE_LC_RUNAWAY = 1u << 5   /* speed running away against the speed loop's torque */
};
#define DRIVE_LC_COUNT 5 /* the ISR's own conditions; the run-away is the speed loop's */
/* the conditions timed by lc_time (the others by lc_track_time) */
#define PROTECT_LC_FAST (DRIVE_LC_CURRENT | DRIVE_LC_DELTA)

/* Which conditions apply (protect_lc_view_t.checks). */
enum {
  PROTECT_LC_CHECK_TORQUE = 1u << 0, /* not in current mode */
  PROTECT_LC_CHECK_FLUX = 1u << 1,   /* a law with a flux (CTRL_CAP_FLUX): flux, observer */
  PROTECT_LC_CHECK_DELTA = 1u << 2   /* ... and a load-angle limit (CTRL_CAP_DELTA) */
};

typedef struct {
  uint32_t n[DRIVE_LC_COUNT]; /* periods each condition has held */
  uint32_t held;              /* conditions whose count is not 0 */
  /* limits of the parameter set in force (protect_lc_configure) */
  float i_lim2;     /* (lc_current i_max)^2 [A^2] */
  float torque_tol; /* lc_track times the torque on MTPA at i_max [N m] */
  float delta_lim;  /* delta_max + lc_delta [rad] */
  float track;      /* lc_track (of the flux reference) */
  float obs_tol;    /* lc_track times the flux on MTPA at i_max [Vs] */
  float n_fast;     /* lc_time in periods */
  float n_track;    /* lc_track_time in periods */
} protect_lc_t;

/* The parameters it needs (at configuration, and when LIVE ones change). */
typedef struct {
  float lc_current, i_max, lc_track, delta_max, lc_delta, lc_time, lc_track_time, ts;
  float torque_scale; /* torque on MTPA at i_max [N m] */
  float flux_scale;   /* its flux amplitude [Vs] */
} protect_lc_cfg_t;

/* What the monitor reads every run period (the law's output). */
typedef struct {
  float i_d, i_q;                       /* [A] */
  float torque, torque_ref;             /* estimate, reference [N m] */
  float torque_min, torque_max;         /* what the law can deliver now [N m] */
  float delta, flux, flux_ref, obs_err; /* [rad], [Vs] */
  uint32_t checks;                      /* PROTECT_LC_CHECK_* */
} protect_lc_view_t;

void protect_lc_configure(protect_lc_t *p, const protect_lc_cfg_t *c);
/* Counts back to 0 (a start). */
void protect_lc_reset(protect_lc_t *p);

/* The conditions that hold now (DRIVE_LC_*). */
static inline uint32_t protect_lc_conditions(const protect_lc_t *p, const protect_lc_view_t *v) {
  uint32_t cond = 0u;
  if (v->i_d * v->i_d + v->i_q * v->i_q > p->i_lim2) {
    /* mut: lost_control_current_off */
    cond |= DRIVE_LC_CURRENT;
  }
  if ((v->checks & PROTECT_LC_CHECK_TORQUE) != 0u) {
    /* the torque the law says it can deliver now, against its estimate,
     * on the scale of the torque at i_max */
    const float t_ref = fd_clampf(v->torque_ref, v->torque_min, v->torque_max);
    if (fabsf(v->torque - t_ref) > p->torque_tol) {
      /* mut: lost_control_torque_off */
      cond |= DRIVE_LC_TORQUE;
    }
  }
  if ((v->checks & PROTECT_LC_CHECK_FLUX) != 0u) {
    /* the SPM laws' load-angle limit (the decoupled DFVC's MTPV limit is
     * its torque margin k_T: its load angle from d is near 90 deg on a
     * reluctance machine) */
    if ((v->checks & PROTECT_LC_CHECK_DELTA) != 0u && fabsf(v->delta) > p->delta_lim) {
      /* mut: lost_control_delta_off */
      cond |= DRIVE_LC_DELTA;
    }
    if (fabsf(v->flux - v->flux_ref) > p->track * v->flux_ref) {
      /* mut: lost_control_flux_off */
      cond |= DRIVE_LC_FLUX;
    }
    /* the observer against its current model, on the scale of the flux at
     * i_max: a detuned model (Rubino 2020, Figs. 19-20) differs by tens of
     * per cent of that at most, a diverging integration by more */
    if (v->obs_err > p->obs_tol) {
      /* mut: lost_control_observer_off */
      cond |= DRIVE_LC_OBSERVER;
    }
  }
  return cond;
}

/* The counts of the conditions that hold (cond) or held: the conditions
 * whose time is up (DRIVE_LC_*, 0 none). Bounded: DRIVE_LC_COUNT passes at
 * most. */
uint32_t protect_lc_count(protect_lc_t *p, uint32_t cond);

/* One run period: the conditions whose time is up (0: none). */
static inline uint32_t protect_lc_step(protect_lc_t *p, const protect_lc_view_t *v) {
  const uint32_t cond = protect_lc_conditions(p, v);
  return (cond | p->held) != 0u ? protect_lc_count(p, cond) : 0u;
}

#endif
