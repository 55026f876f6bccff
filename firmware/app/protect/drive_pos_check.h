/*
 * protect/drive_pos_check.h - position plausibility: the voltage the drive
 * applied against the machine model's at the position source's angle and
 * speed (drive_pos_check.c, docs/faults.md). An owned part of the drive's
 * protections (docs/architecture.md, "Adding a protection"); the file
 * keeps its name because the G474 linker script lists it among the files
 * kept out of the CCM (hal/stm32g4/stm32g474re.ld).
 */
#ifndef FLUXDRIVE_PROTECT_POS_CHECK_H
#define FLUXDRIVE_PROTECT_POS_CHECK_H

#include <stdbool.h>
#include <stdint.h>

#include "math/frames.h"
#include "model/machine.h"

/* What the check takes from the parameter set and the machine: set with
 * the set (protect_pos_configure, drive_protect_configure: full and live
 * sets), off the ISR's path. */
typedef struct {
  uint32_t periods;         /* ISR periods between two checks (the window; the leaky
                               count's time) */
  float t_out;              /* from the sample to the output's centre (1.5 Ts - t_i) [s] */
  float ts;                 /* [s] */
  float rs;                 /* [Ohm] */
  float emf_tol;            /* pos_emf_tol */
  const machine_t *machine; /* the drive's machine model */
  dq_t psi0;                /* its flux at zero current [Vs] */
  float psi_pm;             /* |psi0| [Vs] */
} protect_pos_cfg_t;

typedef struct {
  int32_t n;             /* the leaky count */
  float res;             /* residual / tolerance at the last check (the logs' pos_emf_res) */
  dq_t psi;              /* the model flux at the last check [Vs] */
  bool psi_ok;           /* ... taken in this run (and the window's start below) */
  bool ab_ok;            /* ... in the integral form (the start below taken) */
  ab_t v_sum;            /* the applied voltages summed since the window's start [V] */
  ab_t psi_pm_ab;        /* the window's start: the model flux's magnet part (the flux at zero
                            current) turned to the stator frame [Vs] */
  ab_t psi_i_ab;         /* ... its currents' part [Vs] */
  ab_t i_ab;             /* ... the current [A] */
  float i_abs;           /* ... |i| [A] */
  protect_pos_cfg_t cfg; /* protect_pos_configure */
  /* from cfg, by protect_pos_configure (off the ISR's path) */
  float t_win;    /* the window: periods Ts [s] */
  float inv_t;    /* 1 / t_win [1/s] */
  float tau_int;  /* the integral form's angle: t_out - Ts/2 after the sample [s] */
  int32_t n_trip; /* the leaky count that trips: POS_TRIP_S worth of checks */
} protect_pos_t;

/* Every ISR, where the drive publishes the voltage it will apply
 * (drive_publish): into the window's sum (drive_pos_check.c). Two adds;
 * the window is the `periods` ISRs between two checks. */
static inline void protect_pos_integrate(protect_pos_t *p, ab_t v_ab) {
  p->v_sum.alpha += v_ab.alpha;
  p->v_sum.beta += v_ab.beta;
}

/* What the check reads every check (filled by drive.c, on the telemetry
 * of the last period and the source's speed). */
typedef struct {
  bool active;   /* run now and in the last period, a source that measures
                    with the gates off (not a star-point one), pos_emf_tol > 0
                    and the last DC link finite: otherwise the check restarts */
  bool due;      /* this slow period is one of the check's (the schedule's divider) */
  float omega_e; /* the source's speed [rad/s electrical] */
  float theta_e; /* the angle at the last period's sample [rad] */
  dq_t i_dq;     /* the last period's rotor-frame currents [A] */
  ab_t v_ab;     /* the voltage applied after that sample [V] (the last one
                    protect_pos_integrate summed) */
  float v_dc;    /* [V] */
} protect_pos_view_t;

/* The parameters (drive_protect_configure: every full or live set). */
void protect_pos_configure(protect_pos_t *p, const protect_pos_cfg_t *c);

/* Once per slow period (the drive's schedule table), before the position
 * source's update, after protect_pos_integrate of the period. Returns DRIVE_FAULT_POSITION when the
 * check trips, else 0. */
uint32_t protect_pos_step(protect_pos_t *p, const protect_pos_view_t *v);

#endif
