/*
 * summary.c - metrics of a run as JSON (see summary.h).
 */
#include "summary.h"

#include <cjson/cJSON.h>

static const char *const law_names[] = {"foc", "pi_dfvc", "db_dfvc"};
static const char *const mode_names[] = {"torque", "speed", "current"};

static cJSON *fault_list(uint32_t bits) {
  cJSON *a = cJSON_CreateArray();
  for (unsigned b = 0; b < 32; ++b) {
    if ((bits & (1u << b)) != 0u) {
      cJSON_AddItemToArray(a, cJSON_CreateString(drive_fault_name(1u << b)));
    }
  }
  return a;
}

char *summary_json(const scenario_t *sc, const sil_result_t *r) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "scenario", sc->name);
  cJSON_AddStringToObject(o, "law", law_names[sc->drive.law]);
  cJSON_AddStringToObject(o, "mode", mode_names[sc->drive.mode]);
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
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
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
  cJSON_AddNumberToObject(o, "v_dc", sc->plant.dclink.v_source);
  cJSON_AddNumberToObject(o, "ts", sc->plant.ts);
  cJSON_AddNumberToObject(o, "dead_time", sc->plant.inverter.dead_time);
  cJSON *c = cJSON_AddObjectToObject(o, "controller");
  cJSON_AddStringToObject(c, "law", law_names[d->law]);
  cJSON_AddNumberToObject(c, "rs", d->rs);
  cJSON_AddNumberToObject(c, "ld", d->ld);
  cJSON_AddNumberToObject(c, "lq", d->lq);
  cJSON_AddNumberToObject(c, "lambda_m", d->lambda_m);
  cJSON_AddNumberToObject(c, "i_max", d->i_max);
  cJSON_AddNumberToObject(c, "torque_max", d->torque_max);
  cJSON_AddNumberToObject(c, "speed_max", d->speed_max);
  cJSON_AddNumberToObject(c, "v_margin", d->v_margin);
  cJSON_AddNumberToObject(c, "delta_max", d->delta_max);
  cJSON_AddNumberToObject(c, "vsd_max", d->vsd_max);
  cJSON_AddNumberToObject(c, "flux_min", d->flux_min);
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
}
