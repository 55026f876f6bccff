/*
 * test_dfvc_deadbeat.c - deadbeat laws (29), (33) term by term, the
 * v_sd,max and voltage-circle limits, and the omega_delta target.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "control/dfvc_deadbeat.h"

static machine_t machine; /* Rubino 2020, Table I; the law holds a pointer to it */

static dfvc_deadbeat_t make(void) {
  dfvc_deadbeat_t db;
  assert_int_equal(machine_init_linear(&machine, 21.0f, 7.1f, 0.057f, 0.057f, 0.19f), 0);
  const dfvc_deadbeat_cfg_t cfg = {&machine, 62.5e-6f, 60.0f};
  assert_int_equal(dfvc_deadbeat_init(&db, &cfg), 0);
  return db;
}

static void test_laws_unsaturated(void **state) {
  (void)state;
  const dfvc_deadbeat_t db = make();
  dfvc_deadbeat_in_t in = {0.2130f, 1.60f, 0.2128f, {0.75f, 1.55f}, 219.9f, 300.0f, 179.0f};
  dfvc_deadbeat_out_t out;
  dfvc_deadbeat_step(&db, &in, &out);
  const double vd = 7.1 * 0.75 + (0.2130 - 0.2128) / 62.5e-6; /* (29) */
  const double vq = 7.1 * 1.55 + 300.0 * 0.057 * 0.75 + 219.9 * 0.2128 +
                    0.057 / 62.5e-6 * (1.60 - 1.55); /* (33) */
  assert_true(fabs(out.v_dqs.d - vd) < 1e-3 && fabs(out.v_dqs.q - vq) < 1e-3);
  assert_int_equal(out.sat, 0);
}

static void test_limits(void **state) {
  (void)state;
  const dfvc_deadbeat_t db = make();
  /* flux step beyond v_sd,max, q demand beyond the circle */
  dfvc_deadbeat_in_t in = {0.25f, 3.0f, 0.2128f, {0.75f, 1.55f}, 219.9f, 0.0f, 179.0f};
  dfvc_deadbeat_out_t out;
  dfvc_deadbeat_step(&db, &in, &out);
  assert_true(fabsf(out.v_dqs.d - 60.0f) < 1e-4f);
  assert_true(fabsf(out.v_dqs.q - sqrtf(179.0f * 179.0f - 3600.0f)) < 1e-3f);
  assert_int_equal(out.sat, DFVC_DEADBEAT_SAT_D | DFVC_DEADBEAT_SAT_Q);
  assert_true(out.v_dqs_raw.d > 60.0f && out.v_dqs_raw.q > out.v_dqs.q);
  /* negative flux step, small circle: v_ds limited by v_max itself */
  in.lambda_ref = 0.18f;
  in.iqs_ref = -3.0f;
  in.v_max = 40.0f;
  dfvc_deadbeat_step(&db, &in, &out);
  assert_true(fabsf(out.v_dqs.d + 40.0f) < 1e-4f && fabsf(out.v_dqs.q) < 1e-3f);
}

static void test_omega_delta_target(void **state) {
  (void)state;
  const dfvc_deadbeat_t db = make();
  /* consistent state (sin(delta) = Ls i_qs / lambda_m): delta* = asin(Ls i_qs* / lambda_m) */
  const double iqs1 = 0.19 * sin(0.45) / 0.057;
  const double want = (asin(0.057 * 1.6 / 0.19) - 0.45) / 62.5e-6;
  assert_true(fabs(dfvc_deadbeat_omega_delta_target(&db, 1.6f, (float)iqs1, 0.45f) - want) < 0.5);
  /* steady state (i_qs* = i_qs(t+1)): zero, whatever the parameters */
  assert_true(fabsf(dfvc_deadbeat_omega_delta_target(&db, 1.3f, 1.3f, 0.9f)) < 1e-3f);
  /* saturated argument stays finite */
  assert_true(isfinite(dfvc_deadbeat_omega_delta_target(&db, 100.0f, 0.0f, 0.0f)));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_laws_unsaturated),
      cmocka_unit_test(test_limits),
      cmocka_unit_test(test_omega_delta_target),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
