/*
 * test_truth.c - `fluxdrive-sil --print-truth` (truth.c): the plant's true
 * values a commissioning identifies, from the parsed scenario:
 *  - a linear star-point machine with every non-ideality a bench has: R_s
 *    at the run's temperature (inject.rs_scale), the passive load's
 *    friction, the encoder's offset, the device drops, the cogging torque,
 *    the star point's a and b (plant_aniso_ab);
 *  - a flux-map machine: L_d, L_q at zero current from the map's
 *    interpolant against the map's own grid derivative (the preset syr_1k1)
 *    within 1 %, its PM flux (0 for a SyR);
 *  - defaults: no drops, no cogging.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "plant.h"
#include "plant_fluxmap.h"
#include "scenario.h"
#include "truth.h"

static scenario_t sc;

static cJSON *truth_of(const char *json) {
  char err[512] = "";
  const int r = scenario_parse(json, "truth.json", &sc, err, sizeof err);
  if (r != 0) {
    fprintf(stderr, "%s\n", err);
  }
  assert_int_equal(r, 0);
  char *s = truth_json(&sc);
  assert_non_null(s);
  cJSON *o = cJSON_Parse(s);
  free(s);
  assert_non_null(o);
  return o;
}

static double num(const cJSON *o, const char *sec, const char *key) {
  const cJSON *s = cJSON_GetObjectItemCaseSensitive(o, sec);
  assert_non_null(s);
  const cJSON *v = cJSON_GetObjectItemCaseSensitive(s, key);
  if (!cJSON_IsNumber(v)) {
    fprintf(stderr, "%s.%s missing\n", sec, key);
    fail();
  }
  return v->valuedouble;
}

static void close_to(double got, double want, double rel) {
  if (!(fabs(got - want) <= rel * fabs(want) + 1e-300)) {
    fprintf(stderr, "got %.9g, want %.9g\n", got, want);
    fail();
  }
}

static void linear_machine_with_everything(void **state) {
  (void)state;
  cJSON *o = truth_of(
      "{\"duration\": 0.1, \"machine\": {\"preset\": \"fabbri2022_t51\", \"cogging_amp\": 0.01, "
      "\"cogging_order\": 24, \"cogging_phase\": 0.5}, \"inverter\": {\"model\": \"switching\", "
      "\"dead_time\": 5e-7, \"v_th_sw\": 1.1, \"r_on_sw\": 0.04, \"v_f_diode\": 0.8, \"r_diode\": "
      "0.02}, \"inject\": {\"rs_scale\": 1.25, \"encoder_error\": 0.01, \"passive_load\": "
      "{\"coulomb\": 0.003, \"viscous\": 2e-5}}}");
  const plant_params_t *p = &sc.plant;
  close_to(num(o, "machine", "rs"), 1.25 * p->machine.rs, 1e-12);
  close_to(num(o, "machine", "rs_nominal"), p->machine.rs, 1e-12);
  close_to(num(o, "machine", "ld"), p->machine.ld, 1e-12);
  close_to(num(o, "machine", "lq"), p->machine.lq, 1e-12);
  close_to(num(o, "machine", "lambda_m"), p->machine.lambda_m, 1e-12);
  assert_int_equal((int)num(o, "machine", "pole_pairs"), p->machine.pole_pairs);
  close_to(num(o, "mechanics", "j"), p->mech.j, 1e-12);
  close_to(num(o, "mechanics", "viscous"), p->mech.b + 2e-5, 1e-12);
  close_to(num(o, "mechanics", "coulomb"), 0.003, 1e-12);
  close_to(num(o, "inverter", "dead_time"), 5e-7, 1e-12);
  close_to(num(o, "inverter", "v_th_sw"), 1.1, 1e-12);
  close_to(num(o, "inverter", "r_on_sw"), 0.04, 1e-12);
  close_to(num(o, "inverter", "v_f_diode"), 0.8, 1e-12);
  close_to(num(o, "inverter", "r_diode"), 0.02, 1e-12);
  /* the band (plant_inverter.c): 2 ((td/Ts) v_dc + max threshold) h / L_min */
  const double h = p->ts / p->inverter.substeps;
  const double ld = p->machine.ld / (1.0 + p->machine.ld_sat);
  const double lmin = ld < p->machine.lq ? ld : p->machine.lq;
  close_to(num(o, "inverter", "i_band"), 2.0 * (5e-7 / p->ts * p->dclink.v_source + 1.1) * h / lmin,
           1e-9);
  close_to(num(o, "encoder", "offset"), 0.01, 1e-12);
  close_to(num(o, "encoder", "offset_deg_e"), 0.01 * p->machine.pole_pairs * 57.29577951308232,
           1e-12);
  assert_int_equal((int)num(o, "encoder", "direction"), 1);
  const cJSON *cg = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItem(o, "machine"), "cogging");
  assert_non_null(cg);
  close_to(cJSON_GetObjectItem(cg, "amp")->valuedouble, 0.01, 1e-12);
  assert_int_equal(cJSON_GetObjectItem(cg, "order")->valueint, 24);
  double a, b;
  plant_aniso_ab(&p->machine, &a, &b);
  assert_true(p->machine.aniso.enabled);
  close_to(num(o, "star", "a"), a, 1e-12);
  close_to(num(o, "star", "b"), b, 1e-12);
  cJSON_Delete(o);
}

static void flux_map_inductances(void **state) {
  (void)state;
  cJSON *o = truth_of("{\"duration\": 0.1, \"machine\": {\"preset\": \"syr_1k1\"}}");
  const plant_fluxmap_t *m = sc.plant.machine.map;
  assert_non_null(m);
  /* a wider difference (10 mA) of the forward interpolant: a smooth map
   * has the same slope at zero current */
  double p1, q1, p0, q0;
  plant_fluxmap_flux(m, 1e-2, 0.0, &p1, &q1);
  plant_fluxmap_flux(m, -1e-2, 0.0, &p0, &q0);
  close_to(num(o, "machine", "ld"), (p1 - p0) / 2e-2, 1e-2);
  plant_fluxmap_flux(m, 0.0, 1e-2, &p1, &q1);
  plant_fluxmap_flux(m, 0.0, -1e-2, &p0, &q0);
  close_to(num(o, "machine", "lq"), (q1 - q0) / 2e-2, 1e-2);
  assert_true(num(o, "machine", "ld") > 0.0 && num(o, "machine", "lq") > 0.0);
  plant_fluxmap_flux0(m, &p0, &q0);
  close_to(num(o, "machine", "lambda_m"), p0, 1e-12);
  cJSON_Delete(o);
}

static void defaults_are_ideal(void **state) {
  (void)state;
  cJSON *o = truth_of("{\"duration\": 0.1}");
  assert_true(num(o, "inverter", "v_th_sw") == 0.0 && num(o, "inverter", "r_on_sw") == 0.0 &&
              num(o, "inverter", "v_f_diode") == 0.0 && num(o, "inverter", "r_diode") == 0.0);
  assert_true(sc.plant.mech.cog_amp == 0.0);
  assert_null(cJSON_GetObjectItemCaseSensitive(o, "star"));
  cJSON_Delete(o);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(linear_machine_with_everything),
      cmocka_unit_test(flux_map_inductances),
      cmocka_unit_test(defaults_are_ideal),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
