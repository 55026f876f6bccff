/*
 * sil_commission.c - a scenario's identification run (sil_commission.h).
 */
#include "sil_commission.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#define CM_PI 3.14159265358979323846

void sil_commission_init(sil_commission_t *cm, const sil_commission_list_t *list) {
  /* the record's fields, not its points' storage (written before read) */
  memset(cm, 0, offsetof(sil_commission_t, points));
  cm->done = list->n == 0;
}

static void record_point(sil_commission_t *cm, uint8_t phase, const float r[PROC_RESULTS]) {
  if (cm->n_points >= SIL_COMMISSION_POINTS) {
    cm->points_full = true;
    return;
  }
  sil_commission_point_t *p = &cm->points[cm->n_points++];
  p->step = (uint8_t)cm->k;
  p->phase = phase;
  memcpy(p->result, r, sizeof p->result);
}

/* The step in force from the main loop's telemetry copy: its phase
 * changes (a point each), its end. */
static bool follow(sil_commission_t *cm, const drive_telemetry_t *tm, double t) {
  sil_commission_step_t *s = &cm->step[cm->k];
  const proc_telemetry_t *p = &tm->proc;
  const bool ours = p->id == (uint8_t)s->proc;
  if (cm->waiting) { /* the ISR has taken the request: started, refused or tripped */
    if ((int32_t)(tm->cmd_seq - cm->seq) < 0) {
      return false;
    }
    cm->waiting = false;
    cm->phase = 0u;
  }
  if (ours && p->phase != cm->phase) {
    record_point(cm, cm->phase, cm->last);
    cm->phase = p->phase;
  }
  if (ours) {
    memcpy(cm->last, p->result, sizeof cm->last);
  }
  const bool busy = tm->state == DRIVE_STATE_OFFSET_CAL || tm->state == DRIVE_STATE_IDENT;
  if (busy) {
    return false;
  }
  s->status = ours ? p->status : PROC_ST_ABORTED;
  s->fault = ours && p->status == PROC_ST_FAILED ? p->fault : tm->faults;
  memcpy(s->result, ours ? p->result : cm->last, sizeof s->result);
  if (ours) {
    record_point(cm, cm->phase, p->result);
  }
  s->t1 = t;
  return true;
}

bool sil_commission_main(sil_commission_t *cm, const sil_commission_list_t *list, drive_t *drv,
                         double t, double theta_m) {
  if (cm->done) {
    return false;
  }
  drive_cmd_enable(drv, false);
  if (cm->n > cm->k) { /* one in force */
    if (!follow(cm, drive_telemetry(drv), t)) {
      return true;
    }
    cm->k++;
    if (drv->host.tm.state == DRIVE_STATE_FAULT) { /* the list ends with the fault */
      cm->done = true;
      return false;
    }
  }
  if (cm->k >= list->n) {
    cm->done = true;
    return false;
  }
  sil_commission_step_t *s = &cm->step[cm->k];
  *s = (sil_commission_step_t){
      .proc = list->proc[cm->k], .status = PROC_ST_RUNNING, .t0 = t, .t1 = -1.0};
  cm->n = cm->k + 1;
  cm->theta_prev = theta_m;
  cm->theta_run = 0.0;
  cm->phase = 0u;
  memset(cm->last, 0, sizeof cm->last);
  const char *why = drive_cmd_identify(drv, (proc_id_t)s->proc, NULL);
  if (why != NULL) { /* cannot happen: the scenario's list was checked */
    s->status = PROC_ST_REFUSED;
    s->t1 = t;
    cm->k++;
    return true;
  }
  cm->waiting = true;
  cm->seq = drv->req.seq; /* what the ISR echoes (tm.cmd_seq) once it has taken it */
  return true;
}

void sil_commission_observe(sil_commission_t *cm, const double i_abc[3], double theta_m) {
  if (cm->done || cm->n <= cm->k) {
    return;
  }
  sil_commission_step_t *s = &cm->step[cm->k];
  for (int j = 0; j < 3; ++j) {
    const double a = fabs(i_abc[j]);
    s->i_peak = a > s->i_peak ? a : s->i_peak;
  }
  /* the movement unwrapped: each period's step on the shortest way round
   * (theta_m wraps at 2 pi; a period turns the rotor far less than pi) */
  double d = theta_m - cm->theta_prev;
  d = d > CM_PI ? d - 2.0 * CM_PI : (d < -CM_PI ? d + 2.0 * CM_PI : d);
  cm->theta_prev = theta_m;
  cm->theta_run += d;
  s->move = fabs(cm->theta_run) > s->move ? fabs(cm->theta_run) : s->move;
}
