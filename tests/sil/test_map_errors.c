/*
 * SIL: flux-map files refused by the scenario parser with a message that
 * names the key, the file and the check (and the grid cell where there is
 * one); never a crash, never a silently wrong machine. The blobs are
 * built by the core tests' fixture (a closed-form saturated machine) and
 * corrupted one way each. Also: a good blob gives the drive the map
 * (machine_map) and the plant the same pole pairs.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "../core/flux_map_fixture.h"
#include "sil_test_util.h"

#include <string.h>

static uint32_t blob[FX_WORDS + 4];

static void write_file(const char *path, const void *p, size_t n) {
  FILE *f = fopen(path, "wb");
  assert_non_null(f);
  assert_int_equal(fwrite(p, 1, n, f), n);
  fclose(f);
}

/* Parses a scenario with machine.map = path; returns the error text ("" when accepted). */
static const char *parse_with(const char *path, scenario_t *sc) {
  static char err[1024];
  char json[1024];
  snprintf(json, sizeof json,
           "{\"name\": \"map\", \"duration\": 0.01, \"machine\": {\"map\": \"%s\", \"rs\": 1.0}}",
           path);
  err[0] = '\0';
  if (scenario_parse(json, "maps.json", sc, err, sizeof err) == 0) {
    err[0] = '\0';
  }
  return err;
}

static void expect_refused(const char *path, const char *what) {
  scenario_t sc;
  const char *e = parse_with(path, &sc);
  printf("%s\n", e);
  if (strstr(e, "machine.map") == NULL || strstr(e, path) == NULL || strstr(e, what) == NULL) {
    fail_msg("expected machine.map, %s and \"%s\" in: %s", path, what, e);
  }
}

static void accepted_map(void **state) {
  (void)state;
  const uint32_t n = fx_build(&FX_PM, blob);
  write_file("map_ok.fdmap", blob, n);
  scenario_t sc;
  const char *e = parse_with("map_ok.fdmap", &sc);
  assert_string_equal(e, "");
  assert_non_null(sc.drive.machine_map);
  assert_non_null(sc.plant.machine.map);
  assert_int_equal(sc.plant.machine.pole_pairs, 2);
  assert_true(sc.drive.pole_pairs > 1.99f && sc.drive.pole_pairs < 2.01f);
  assert_int_equal(sc.drive.machine_map[FX_WORDS - 1], blob[FX_WORDS - 1]);
}

static void refused_maps(void **state) {
  (void)state;
  expect_refused("no_such_map.fdmap", "cannot open");
  uint32_t n = fx_build(&FX_PM, blob);
  write_file("map.txt", blob, n);
  expect_refused("map.txt", "unknown map format");
  write_file("map_short.fdmap", blob, n - 6u);
  expect_refused("map_short.fdmap", "whole number of 32-bit words");
  write_file("map_trunc.fdmap", blob, n - 8u);
  expect_refused("map_trunc.fdmap", "size does not match");
  blob[40] ^= 1u;
  write_file("map_crc.fdmap", blob, n);
  expect_refused("map_crc.fdmap", "CRC mismatch");
  n = fx_build(&FX_PM, blob);
  blob[0] = 0x12345678u;
  write_file("map_magic.fdmap", blob, n);
  expect_refused("map_magic.fdmap", "not a flux map");
  n = fx_build(&FX_PM, blob);
  fx_put_f(blob, 12 + 5 * FX_N + 9, NAN);
  fx_reseal(blob);
  write_file("map_nan.fdmap", blob, n);
  expect_refused("map_nan.fdmap", "flux value not finite or beyond 1000 Vs at grid cell (9, 5)");
  /* finite but beyond any machine: they overflowed the lookups (found by
   * tests/fuzz fuzz_fluxmap: a torque of inf from 1.6e32 pole pairs) */
  n = fx_build(&FX_PM, blob);
  fx_put_f(blob, 12 + 5 * FX_N + 9, 1e4);
  fx_reseal(blob);
  write_file("map_huge.fdmap", blob, n);
  expect_refused("map_huge.fdmap", "beyond 1000 Vs at grid cell (9, 5)");
  n = fx_build(&FX_PM, blob);
  fx_put_f(blob, 7, 1.6e32); /* pole pairs */
  fx_reseal(blob);
  write_file("map_poles.fdmap", blob, n);
  expect_refused("map_poles.fdmap", "or beyond 1e5 A or 100 pole pairs");
  n = fx_build(&FX_PM, blob);
  fx_put_f(blob, 9, 1e6); /* the i_d step: the grid ends far beyond 1e5 A */
  fx_reseal(blob);
  write_file("map_grid.fdmap", blob, n);
  expect_refused("map_grid.fdmap", "or beyond 1e5 A or 100 pole pairs");
  n = fx_build(&FX_PM, blob);
  fx_break_pd(blob);
  write_file("map_pd.fdmap", blob, n);
  expect_refused("map_pd.fdmap", "not positive definite at grid cell (0, 12)");
  /* a map with linear keys: refused, the key named */
  n = fx_build(&FX_PM, blob);
  write_file("map_ok2.fdmap", blob, n);
  scenario_t sc;
  char err[512];
  assert_int_not_equal(
      scenario_parse("{\"duration\": 0.01, \"machine\": {\"map\": \"map_ok2.fdmap\", \"ld\": 0.1}}",
                     "maps.json", &sc, err, sizeof err),
      0);
  assert_non_null(strstr(err, "machine.ld: a flux-map machine takes"));
  /* detuning factors that would act on nothing */
  assert_int_not_equal(scenario_parse("{\"duration\": 0.01, \"machine\": {\"map\": "
                                      "\"map_ok2.fdmap\"}, \"controller\": {\"estimates\": "
                                      "{\"ld_scale\": 1.2}}}",
                                      "maps.json", &sc, err, sizeof err),
                       0);
  assert_non_null(strstr(err, "controller.estimates.ld_scale: a flux-map machine's model"));
  /* pole pairs other than the map's */
  assert_int_not_equal(scenario_parse("{\"duration\": 0.01, \"machine\": {\"map\": "
                                      "\"map_ok2.fdmap\", \"pole_pairs\": 3}}",
                                      "maps.json", &sc, err, sizeof err),
                       0);
  printf("%s\n", err);
  /* issue 23, point 13: both counts named */
  assert_non_null(strstr(err, "machine.pole_pairs: 3, but the map file map_ok2.fdmap has 2"));
  /* the map's own count given again: accepted */
  assert_int_equal(scenario_parse("{\"duration\": 0.01, \"machine\": {\"map\": "
                                  "\"map_ok2.fdmap\", \"pole_pairs\": 2}}",
                                  "maps.json", &sc, err, sizeof err),
                   0);
  /* the drive's own map (controller.map): a map machine's, the same pole pairs */
  assert_int_not_equal(scenario_parse("{\"duration\": 0.01, \"controller\": {\"map\": "
                                      "\"map_ok2.fdmap\"}}",
                                      "maps.json", &sc, err, sizeof err),
                       0);
  assert_non_null(strstr(err, "controller.map: needs a flux-map machine"));
  assert_int_equal(scenario_parse("{\"duration\": 0.01, \"machine\": {\"map\": "
                                  "\"map_ok2.fdmap\"}, \"controller\": {\"map\": "
                                  "\"map_ok2.fdmap\"}}",
                                  "maps.json", &sc, err, sizeof err),
                   0);
  assert_non_null(sc.drive.machine_map);
}

/* issue 23, point 14: the drive's current limit inside the map's grid
 * (the fixture's: i_d, i_q in [-FX_I, FX_I] = [-6, 6] A) */
static void i_max_within_the_map(void **state) {
  (void)state;
  const uint32_t n = fx_build(&FX_PM, blob);
  write_file("map_range.fdmap", blob, n);
  static scenario_t sc;
  char err[1024] = "", json[512];
  const double ok = FX_I, bad = FX_I * 1.05;
  snprintf(json, sizeof json,
           "{\"duration\": 0.01, \"machine\": {\"map\": \"map_range.fdmap\"}, \"controller\": "
           "{\"i_max\": %g, \"i_trip\": 9}, \"sensors\": {\"i_full_scale\": 20}}",
           ok);
  if (scenario_parse(json, "maps.json", &sc, err, sizeof err) != 0) {
    fail_msg("i_max %g A on a +-%g A grid refused: %s", ok, FX_I, err);
  }
  snprintf(json, sizeof json,
           "{\"duration\": 0.01, \"machine\": {\"map\": \"map_range.fdmap\"}, \"controller\": "
           "{\"i_max\": %g, \"i_trip\": 9}, \"sensors\": {\"i_full_scale\": 20}}",
           bad);
  assert_int_not_equal(scenario_parse(json, "maps.json", &sc, err, sizeof err), 0);
  printf("%s\n", err);
  char want[160];
  snprintf(want, sizeof want, "controller.i_max: %g A reaches beyond the flux map", bad);
  assert_non_null(strstr(err, want));
  snprintf(want, sizeof want, "(i_d %g .. %g A, i_q %g .. %g A)", -FX_I, FX_I, -FX_I, FX_I);
  assert_non_null(strstr(err, want));
  assert_non_null(strstr(err, "map_range.fdmap"));
  snprintf(want, sizeof want, "at most %g A with this map", FX_I);
  assert_non_null(strstr(err, want));
}

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(accepted_map), cmocka_unit_test(refused_maps),
                                     cmocka_unit_test(i_max_within_the_map)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
