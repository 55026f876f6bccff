/*
 * truth.c - the plant's true values a commissioning identifies (truth.h),
 * read from the scenario's plant structs (plant.h), at the run's start
 * (t = 0) where a parameter fault's profile changes them over the run; the
 * profile's bounds are printed with it when it is not constant.
 *   machine: R_s (winding temperature: faults.rs_scale), pole pairs, the
 *     PM flux (linear: lambda_m times faults.lambda_m_scale; flux map:
 *     psi_d at zero current), L_d, L_q: the incremental inductances at zero
 *     current (linear: ld, lq; flux map: central differences of the map's
 *     forward interpolant at i = 0, +-1 mA, with the cross term), cogging torque;
 *   mechanics: J, viscous friction (mech.b plus the passive load's
 *     faults.viscous), Coulomb friction (faults.coulomb);
 *   inverter: dead time, the device drops (plant_inverter_t) and the band
 *     i_band [A] over which both models take the dead time's sign and the
 *     thresholds in (the initialised plant's, plant_inverter.c): the
 *     voltage-error curve of docs/machines.md;
 *   encoder: counts per turn, its mounting offset (inject.encoder_error at
 *     t = 0 [rad mech], and in electrical degrees), its direction (the
 *     plant's encoder counts with the rotor: +1);
 *   star point (enabled): a and b of (3.7) (plant_aniso_ab, normalised to
 *     v_dc) and the saliency axis' shift.
 */
#include "truth.h"

#include <cjson/cJSON.h>
#include <stdio.h>

#include "plant.h"
#include "plant_fluxmap.h"
#include "profile.h"

/* A profile's value at t = 0 (1 or 0 without terms: `none`), its bounds
 * added as NAME_range when it is not constant. */
static double at_start(cJSON *o, const char *name, const profile_t *p, double none) {
  if (p->n == 0) {
    return none;
  }
  double lo, hi;
  profile_bounds(p, &lo, &hi);
  if (lo != hi) {
    char key[64];
    snprintf(key, sizeof key, "%s_range", name);
    cJSON *r = cJSON_AddArrayToObject(o, key);
    cJSON_AddItemToArray(r, cJSON_CreateNumber(lo));
    cJSON_AddItemToArray(r, cJSON_CreateNumber(hi));
  }
  return profile_eval(p, 0.0);
}

/* Incremental inductances of a flux map at zero current [H]. */
static void map_l0(const plant_fluxmap_t *m, double h, double l[2][2]) {
  double pdp, pqp, pdm, pqm;
  for (int c = 0; c < 2; c++) {
    plant_fluxmap_flux(m, c == 0 ? h : 0.0, c == 1 ? h : 0.0, &pdp, &pqp);
    plant_fluxmap_flux(m, c == 0 ? -h : 0.0, c == 1 ? -h : 0.0, &pdm, &pqm);
    l[0][c] = (pdp - pdm) / (2.0 * h);
    l[1][c] = (pqp - pqm) / (2.0 * h);
  }
}

char *truth_json(const scenario_t *sc) {
  const plant_params_t *p = &sc->plant;
  const plant_machine_t *m = &p->machine;
  const plant_faults_t *f = &p->faults;
  cJSON *o = cJSON_CreateObject();
  cJSON_AddStringToObject(o, "scenario", sc->name);
  cJSON *mo = cJSON_AddObjectToObject(o, "machine");
  cJSON_AddStringToObject(mo, "kind", m->map != NULL ? "flux_map" : "linear");
  cJSON_AddNumberToObject(mo, "pole_pairs", m->pole_pairs);
  const double rs_scale = at_start(mo, "rs_scale", &f->rs_scale, 1.0);
  cJSON_AddNumberToObject(mo, "rs", m->rs * rs_scale);
  cJSON_AddNumberToObject(mo, "rs_nominal", m->rs);
  if (m->map != NULL) {
    double pd, pq, l[2][2];
    plant_fluxmap_flux0(m->map, &pd, &pq);
    map_l0(m->map, 1e-3, l);
    cJSON_AddNumberToObject(mo, "lambda_m", pd);
    cJSON_AddNumberToObject(mo, "psi_q0", pq);
    cJSON_AddNumberToObject(mo, "ld", l[0][0]);
    cJSON_AddNumberToObject(mo, "lq", l[1][1]);
    cJSON_AddNumberToObject(mo, "ldq", 0.5 * (l[0][1] + l[1][0]));
    cJSON_AddStringToObject(mo, "map", sc->map_file);
  } else {
    const double lm_scale = at_start(mo, "lambda_m_scale", &f->lambda_m_scale, 1.0);
    cJSON_AddNumberToObject(mo, "lambda_m", m->lambda_m * lm_scale);
    cJSON_AddNumberToObject(mo, "ld", m->ld);
    cJSON_AddNumberToObject(mo, "lq", m->lq);
    if (m->ld_sat > 0.0) {
      cJSON_AddNumberToObject(mo, "ld_sat", m->ld_sat);
      cJSON_AddNumberToObject(mo, "i_sat", m->i_sat);
    }
  }
  cJSON *cg = cJSON_AddObjectToObject(mo, "cogging");
  cJSON_AddNumberToObject(cg, "amp", p->mech.cog_amp);
  cJSON_AddNumberToObject(cg, "order", p->mech.cog_order);
  cJSON_AddNumberToObject(cg, "phase", p->mech.cog_phase);

  cJSON *me = cJSON_AddObjectToObject(o, "mechanics");
  cJSON_AddStringToObject(me, "mode", p->mech.mode == PLANT_MECH_FREE ? "free" : "imposed");
  cJSON_AddNumberToObject(me, "j", p->mech.j);
  const double visc = at_start(me, "viscous_added", &f->viscous, 0.0);
  cJSON_AddNumberToObject(me, "viscous", p->mech.b + visc);
  cJSON_AddNumberToObject(me, "coulomb", at_start(me, "coulomb", &f->coulomb, 0.0));

  cJSON *iv = cJSON_AddObjectToObject(o, "inverter");
  cJSON_AddStringToObject(iv, "model",
                          p->inverter.model == PLANT_INV_AVERAGE ? "average" : "switching");
  cJSON_AddNumberToObject(iv, "dead_time", p->inverter.dead_time);
  cJSON_AddNumberToObject(iv, "ts", p->ts);
  cJSON_AddNumberToObject(iv, "v_dc", p->dclink.v_source);
  cJSON_AddNumberToObject(iv, "v_th_sw", p->inverter.v_th_sw);
  cJSON_AddNumberToObject(iv, "r_on_sw", p->inverter.r_on_sw);
  cJSON_AddNumberToObject(iv, "v_f_diode", p->inverter.v_f_diode);
  cJSON_AddNumberToObject(iv, "r_diode", p->inverter.r_diode);
  static plant_t pl; /* large (the noise tables): not on the stack */
  const char *field = NULL;
  if (plant_init(&pl, p, &field) == 0) {
    cJSON_AddNumberToObject(iv, "i_band", 1.0 / pl.aux.inv_band);
  }

  cJSON *en = cJSON_AddObjectToObject(o, "encoder");
  cJSON_AddNumberToObject(en, "cpr", p->sensors.encoder_cpr);
  const double off = at_start(en, "offset", &sc->encoder_error, 0.0);
  cJSON_AddNumberToObject(en, "offset", off);
  cJSON_AddNumberToObject(en, "offset_deg_e", off * m->pole_pairs * 57.29577951308232);
  cJSON_AddNumberToObject(en, "direction", 1);

  if (m->aniso.enabled) {
    double a, b;
    plant_aniso_ab(m, &a, &b);
    cJSON *st = cJSON_AddObjectToObject(o, "star");
    cJSON_AddNumberToObject(st, "a", a);
    cJSON_AddNumberToObject(st, "b", b);
    cJSON_AddNumberToObject(st, "shift", m->aniso.shift);
  }
  char *s = cJSON_Print(o);
  cJSON_Delete(o);
  return s;
}
