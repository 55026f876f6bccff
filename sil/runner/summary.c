/*
 * summary.c - metrics of a run as JSON (see summary.h).
 */
#include "summary.h"

#include <cjson/cJSON.h>
#include <stddef.h>

#include "can_codec.h"
#include "can_proto.h"

static cJSON *fault_list(uint32_t bits) {
  cJSON *a = cJSON_CreateArray();
  for (unsigned b = 0; b < 32; ++b) {
    if ((bits & (1u << b)) != 0u) {
      cJSON_AddItemToArray(a, cJSON_CreateString(drive_fault_name(1u << b)));
    }
  }
  return a;
}

static const char *const proc_status_names[] = {"idle",   "running", "done",
                                                "failed", "aborted", "refused"};

static cJSON *float_array(const float *v, int n) {
  cJSON *a = cJSON_CreateArray();
  for (int k = 0; k < n; ++k) {
    cJSON_AddItemToArray(a, cJSON_CreateNumber((double)v[k]));
  }
  return a;
}

/* The identification run (sil_commission.h): each procedure's record and
 * its points. */
static cJSON *commission_json(const sil_commission_t *cm) {
  cJSON *a = cJSON_CreateArray();
  for (int k = 0; k < cm->n; ++k) {
    const sil_commission_step_t *s = &cm->step[k];
    const proc_row_t *row = proc_row((proc_id_t)s->proc);
    cJSON *e = cJSON_CreateObject();
    cJSON_AddStringToObject(e, "proc", row != NULL ? row->name : "?");
    cJSON_AddStringToObject(e, "status",
                            (unsigned)s->status < 6u ? proc_status_names[s->status] : "?");
    cJSON_AddItemToObject(e, "fault", fault_list(s->fault));
    cJSON_AddItemToObject(e, "result", float_array(s->result, PROC_RESULTS));
    cJSON_AddNumberToObject(e, "t0", s->t0);
    cJSON_AddNumberToObject(e, "t1", s->t1);
    cJSON_AddNumberToObject(e, "i_peak", s->i_peak);
    cJSON_AddNumberToObject(e, "move", s->move);
    cJSON *pts = cJSON_AddArrayToObject(e, "points");
    for (int j = 0; j < cm->n_points; ++j) {
      const sil_commission_point_t *p = &cm->points[j];
      if (p->step == (uint8_t)k) {
        cJSON *q = cJSON_CreateArray();
        cJSON_AddItemToArray(q, cJSON_CreateNumber((double)p->phase));
        for (int x = 0; x < PROC_RESULTS; ++x) {
          cJSON_AddItemToArray(q, cJSON_CreateNumber((double)p->result[x]));
        }
        cJSON_AddItemToArray(pts, q);
      }
    }
    cJSON_AddBoolToObject(e, "points_full", cm->points_full);
    cJSON_AddItemToArray(a, e);
  }
  return a;
}

char *summary_json(const scenario_t *sc, const sil_result_t *r) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "scenario", sc->name);
  cJSON_AddStringToObject(o, "law", drive_law_name((unsigned)sc->drive.law));
  cJSON_AddStringToObject(o, "mode", drive_mode_name((unsigned)sc->drive.mode));
  cJSON_AddStringToObject(o, "inverter",
                          sc->plant.inverter.model == PLANT_INV_AVERAGE ? "average" : "switching");
  cJSON_AddNumberToObject(o, "sim_time", r->sim_time);
  cJSON_AddNumberToObject(o, "steps", (double)r->steps);
  cJSON_AddNumberToObject(o, "wall_time", r->wall_time);
  cJSON_AddNumberToObject(o, "real_time_factor", r->real_time_factor);
  cJSON_AddNumberToObject(o, "final_speed_rpm", r->final_speed * 30.0 / 3.14159265358979);
  cJSON_AddNumberToObject(o, "final_speed_ref_rpm", r->final_speed_ref * 30.0 / 3.14159265358979);
  cJSON_AddNumberToObject(o, "max_speed_rpm", r->max_speed * 30.0 / 3.14159265358979);
  cJSON_AddNumberToObject(o, "final_torque", r->final_torque);
  cJSON_AddNumberToObject(o, "max_phase_current", r->max_phase_current);
  cJSON_AddNumberToObject(o, "max_phase_current_t", r->max_phase_current_t);
  cJSON_AddNumberToObject(o, "i_max", sc->drive.i_max);
  cJSON_AddNumberToObject(o, "v_dc_min", r->v_dc_min);
  cJSON_AddNumberToObject(o, "v_dc_max", r->v_dc_max);
  cJSON_AddStringToObject(o, "final_state", drive_state_name(r->final_state));
  cJSON_AddItemToObject(o, "faults", fault_list(r->faults));
  cJSON_AddItemToObject(o, "faults_seen", fault_list(r->faults_seen));
  cJSON_AddNumberToObject(o, "first_fault_t", r->first_fault_t);
  cJSON_AddNumberToObject(o, "watchdog_resets", (double)r->watchdog_resets);
  cJSON_AddNumberToObject(o, "first_watchdog_t", r->first_watchdog_t);
  cJSON_AddNumberToObject(o, "pwm_clamped", (double)r->pwm_clamped);
  cJSON_AddNumberToObject(o, "voltage_balance_max", r->voltage_balance_max);
  if (sc->commission.n > 0) {
    cJSON_AddItemToObject(o, "commission", commission_json(&r->commission));
  }
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
}

/* One parameter as JSON: a number, or the name of a law, mode, source. */
static void add_param(cJSON *o, const drive_config_t *d, const drive_param_t *p) {
  const float v = drive_param_get(d, p);
  switch ((drive_param_type_t)p->type) {
  case DRIVE_PARAM_LAW:
    cJSON_AddStringToObject(o, p->name, drive_law_name((unsigned)v));
    break;
  case DRIVE_PARAM_MODE:
    cJSON_AddStringToObject(o, p->name, drive_mode_name((unsigned)v));
    break;
  case DRIVE_PARAM_POS:
    cJSON_AddStringToObject(o, p->name, drive_pos_source_name((unsigned)v));
    break;
  default:
    cJSON_AddNumberToObject(o, p->name, (double)v);
    break;
  }
}

char *config_json(const scenario_t *sc) {
  const plant_machine_t *m = &sc->plant.machine;
  const drive_config_t *d = &sc->drive;
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "scenario", sc->name);
  cJSON *pm = cJSON_AddObjectToObject(o, "machine");
  cJSON_AddNumberToObject(pm, "pole_pairs", m->pole_pairs);
  cJSON_AddNumberToObject(pm, "rs", m->rs);
  cJSON_AddNumberToObject(pm, "ld", m->ld);
  cJSON_AddNumberToObject(pm, "lq", m->lq);
  cJSON_AddNumberToObject(pm, "lambda_m", m->lambda_m);
  cJSON_AddNumberToObject(pm, "j", sc->plant.mech.j);
  cJSON_AddStringToObject(pm, "kind", d->machine_map != NULL ? "flux_map" : "linear");
  if (d->machine_map != NULL) {
    cJSON_AddStringToObject(pm, "map", sc->map_file);
  }
  cJSON_AddNumberToObject(o, "v_dc", sc->plant.dclink.v_source);
  cJSON_AddNumberToObject(o, "ts", sc->plant.ts);
  cJSON_AddNumberToObject(o, "dead_time", sc->plant.inverter.dead_time);
  cJSON *b = cJSON_AddObjectToObject(o, "board");
  cJSON_AddNumberToObject(b, "duty_min", sc->board.duty_min);
  cJSON_AddNumberToObject(b, "duty_max", sc->board.duty_max);
  cJSON_AddNumberToObject(b, "timer_counts", sc->board.timer_counts);
  cJSON_AddNumberToObject(b, "watchdog_ms", sc->board.watchdog_ms);
  /* the controller: every row of the parameter table */
  cJSON *c = cJSON_AddObjectToObject(o, "controller");
  unsigned n;
  const drive_param_t *t = drive_params_table(&n);
  for (unsigned i = 0; i < n; ++i) {
    add_param(c, d, &t[i]);
  }
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
}

/* The parameter table and the drive's named values (fluxdrive params). */
char *params_json(void) {
  cJSON *o = cJSON_CreateObject();
  cJSON *arr = cJSON_AddArrayToObject(o, "params");
  unsigned n;
  const drive_param_t *t = drive_params_table(&n);
  static const char *const types[] = {"f32", "u16", "u32", "law", "mode", "pos_source", "map"};
  static const char *const access[] = {"ro", "idle", "live"};
  for (unsigned i = 0; i < n; ++i) {
    cJSON *p = cJSON_CreateObject();
    cJSON_AddNumberToObject(p, "id", t[i].id);
    cJSON_AddStringToObject(p, "name", t[i].name);
    cJSON_AddStringToObject(p, "type", types[t[i].type]);
    cJSON_AddStringToObject(p, "unit", t[i].unit);
    cJSON_AddNumberToObject(p, "default", (double)t[i].def);
    cJSON_AddNumberToObject(p, "min", (double)t[i].min);
    cJSON_AddNumberToObject(p, "max", (double)t[i].max);
    cJSON_AddStringToObject(p, "access", access[t[i].access]);
    cJSON_AddStringToObject(p, "scenario", t[i].scenario);
    cJSON_AddStringToObject(p, "doc", t[i].doc);
    cJSON_AddItemToArray(arr, p);
  }
  cJSON *pp = cJSON_AddArrayToObject(o, "can_params");
  for (unsigned id = 0; id < 256u; ++id) {
    const char *name = can_proto_param_name((uint8_t)id);
    if (name != NULL) {
      cJSON *p = cJSON_CreateObject();
      cJSON_AddNumberToObject(p, "id", id);
      cJSON_AddStringToObject(p, "name", name);
      cJSON_AddStringToObject(p, "access", id == CAN_PROTO_PARAM_FIRST ? "ro" : "live");
      cJSON_AddItemToArray(pp, p);
    }
  }
  struct {
    const char *key;
    const char *(*name)(unsigned);
    unsigned count;
  } lists[] = {{"laws", drive_law_name, DRIVE_LAW_COUNT},
               {"modes", drive_mode_name, DRIVE_MODE_COUNT},
               {"states", drive_state_name, DRIVE_STATE_COUNT},
               {"pos_sources", drive_pos_source_name, POS_SOURCE_COUNT}};
  for (size_t l = 0; l < sizeof lists / sizeof lists[0]; ++l) {
    cJSON *a = cJSON_AddArrayToObject(o, lists[l].key);
    for (unsigned v = 0; v < lists[l].count; ++v) {
      cJSON_AddItemToArray(a, cJSON_CreateString(lists[l].name(v)));
    }
  }
  /* the procedures (proc.h PROC_LIST): CMD_PROC's and TM_PROC's value
   * tables, the commissioning's identification procedures */
  cJSON *pr = cJSON_AddArrayToObject(o, "procs");
  for (unsigned k = 0; k < (unsigned)PROC_COUNT; ++k) {
    const proc_row_t *r = proc_row((proc_id_t)k);
    cJSON *p = cJSON_CreateObject();
    cJSON_AddStringToObject(p, "name", r->name);
    cJSON_AddBoolToObject(p, "ident", (r->caps & PROC_CAP_IDENT) != 0u);
    cJSON_AddItemToArray(pr, p);
  }
  cJSON *f = cJSON_AddArrayToObject(o, "faults");
  for (unsigned b = 0; b < (unsigned)DRIVE_FAULT_COUNT; ++b) {
    cJSON_AddItemToArray(f, cJSON_CreateString(drive_fault_name(1u << b)));
  }
  cJSON *res = cJSON_AddArrayToObject(o, "can_results");
  for (unsigned r = 0; r < CAN_RESULT_COUNT; ++r) {
    cJSON_AddItemToArray(res, cJSON_CreateString(can_codec_result_name(r)));
  }
  cJSON_AddNumberToObject(o, "can_keep", CAN_KEEP);
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
}

char *preempt_json(const sil_preempt_result_t *r) {
  cJSON *o = cJSON_CreateObject();
  const struct {
    const char *key;
    uint64_t v;
  } n[] = {{"periods", r->periods},
           {"main_iterations", r->main_iterations},
           {"commands", r->commands},
           {"clears", r->clears},
           {"fault_requests", r->fault_requests},
           {"param_writes", r->param_writes},
           {"param_refused", r->param_refused},
           {"tm_reads", r->tm_reads},
           {"tm_retries", r->tm_retries},
           {"tm_failed", r->tm_failed},
           {"tm_torn", r->tm_torn},
           {"in_publication", r->in_publication},
           {"cfg_in_publication", r->cfg_in_publication},
           {"starts", r->starts},
           {"trips", r->trips},
           {"violations", r->violations}};
  for (size_t i = 0; i < sizeof n / sizeof n[0]; ++i) {
    cJSON_AddNumberToObject(o, n[i].key, (double)n[i].v);
  }
  cJSON_AddStringToObject(o, "first_violation", r->first_violation);
  cJSON_AddNumberToObject(o, "wall_s", r->wall_s);
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
}
