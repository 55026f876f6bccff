/*
 * sil_commission.h - a scenario's identification run (key "commission",
 * docs/commissioning.md): the runner's main loop posts each procedure in
 * turn with the drive disabled (drive_cmd_identify), as `fluxdrive
 * commission` does over CAN, and records what each published and what the
 * plant did meanwhile (the true peak current and rotor movement). The
 * references' enable is posted only once the last has ended.
 */
#ifndef FD_SIL_COMMISSION_H
#define FD_SIL_COMMISSION_H

#include <stdbool.h>
#include <stdint.h>

#include "drive.h"

#define SIL_COMMISSION_MAX    16   /* procedures in one scenario */
#define SIL_COMMISSION_POINTS 1024 /* points recorded over a run (all procedures) */

/* The scenario's list (scenario_t.commission). */
typedef struct {
  int n;
  int proc[SIL_COMMISSION_MAX]; /* proc_id_t */
} sil_commission_list_t;

/* One point: a procedure's results when its phase changed (or it ended). */
typedef struct {
  uint8_t step;  /* index in the list */
  uint8_t phase; /* the phase whose results these are */
  float result[PROC_RESULTS];
} sil_commission_point_t;

/* One procedure's record. */
typedef struct {
  int proc;       /* proc_id_t */
  int status;     /* PROC_ST_* at its end (PROC_ST_RUNNING: the run ended first) */
  uint32_t fault; /* its fault bits (PROC_ST_FAILED), or the drive's at the end */
  float result[PROC_RESULTS];
  double t0, t1; /* posted, ended [s] (t1 < 0: not ended) */
  double i_peak; /* the true largest phase current while it ran [A] */
  double move;   /* the true largest rotor movement from its start [rad mech] */
} sil_commission_step_t;

/* The run's record and the main loop's progress through the list. */
typedef struct {
  int n;                    /* steps begun */
  int k;                    /* the step in force (n: none left) */
  bool waiting;             /* posted, the ISR not yet seen taking it (telemetry cmd_seq) */
  uint32_t seq;             /* the command block's sequence that posted it */
  bool done;                /* the list has ended (or was empty) */
  uint8_t phase;            /* the step's phase last seen */
  float last[PROC_RESULTS]; /* and its results then */
  double theta0;            /* the rotor's true angle at the step's start [rad mech] */
  sil_commission_step_t step[SIL_COMMISSION_MAX];
  int n_points;
  bool points_full; /* points were dropped (SIL_COMMISSION_POINTS) */
  sil_commission_point_t points[SIL_COMMISSION_POINTS];
} sil_commission_t;

void sil_commission_init(sil_commission_t *cm, const sil_commission_list_t *list);
/* The main loop at t: the next procedure posted when the one in force has
 * ended (by the main loop's telemetry copy). True while the list runs (the
 * references' enable held off). */
bool sil_commission_main(sil_commission_t *cm, const sil_commission_list_t *list, drive_t *drv,
                         double t, double theta_m);
/* Every period: the plant's truth while a procedure runs. */
void sil_commission_observe(sil_commission_t *cm, const double i_abc[3], double theta_m);

#endif
