/*
 * The rs identification (proc_rs.c) without the SIL: on a small standstill
 * R-L model (alpha-beta, one period's delay) with an inverter voltage error
 * per phase (linear below a knee current, a plateau above, as dead time),
 * current noise and quantisation, R_s within 2 % and the voltage error at
 * the top level within 5 % of the model's (the truth: the model's
 * parameters, not what the code printed); the current within its limit;
 * the report points; the overcurrent trip; the refusal of a bad level
 * count.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "drive.h"
#include "proc.h"
#include "proc_fixture.h"

typedef struct {
  PROC_FIXTURE_FIELDS
  pos_estimate_t pos;
} fixture_t;

static fixture_t fx;

#include "proc_rl_model.h" /* R, L, the voltage error's plateau V0 and knee per phase */

static void fixture(float r, float l) {
  memset(&fx, 0, sizeof fx);
  drive_config_default(&fx.cfg);
  fx.cfg.pos_source = POS_SOURCE_ENCODER;
  fx.cfg.i_max = 10.0f;
  fx.cfg.rs = r * 1.3f; /* the controller's guesses: not the truth */
  fx.cfg.ld = l * 0.7f;
  fx.cfg.lq = l * 0.7f;
  fx.cfg.id_rs_current = 8.0f;
  proc_fixture_bind(&fx);
  fx.s.valid = true;
  fx.s.v_dc = 48.0f;
}

/* Runs the procedure on the model to its end (or max periods): its return. */
static int run(model_t *m, proc_telemetry_t *tm, uint32_t max, unsigned *points) {
  const proc_row_t *row = proc_row(PROC_RS);
  row->init(&fx.st, &fx.su);
  int res = PROC_RUNNING;
  uint8_t phase = 0u;
  *points = 0u;
  for (uint32_t k = 0; k < max && res == PROC_RUNNING; ++k) {
    const proc_in_t in = {&fx.s, {model_meas(m, m->i_a), model_meas(m, m->i_b)}, 24.0f, &fx.pos};
    proc_out_t out;
    res = row->step(&fx.st, &fx.su, &in, &out);
    row->publish(&fx.st, tm);
    if (tm->phase != phase) {
      phase = tm->phase;
      ++*points;
    }
    if (res == PROC_FAILED) {
      tm->fault = out.fault;
      break;
    }
    const float vm = sqrtf(out.v_ab.alpha * out.v_ab.alpha + out.v_ab.beta * out.v_ab.beta);
    assert_true(vm <= 24.0f * 1.0001f);
    model_step(m, out.apply ? out.v_ab : (ab_t){0.0f, 0.0f}, fx.cfg.ts);
  }
  return res;
}

static void resistance_and_voltage_error_separated(void **state) {
  (void)state;
  static const float rs[] = {0.05f, 0.5f, 3.0f};
  static const float ls[] = {1e-4f, 1e-3f, 2e-2f};
  for (unsigned c = 0; c < 3u; ++c) {
    fixture(rs[c], ls[c]);
    model_t m = {rs[c], ls[c], ls[c],      0.4f, 0.6f, 0.02f,       0.01f,
                 0.0f,  0.0f,  12345u + c, 0.0f, 0,    {0.0f, 0.0f}};
    proc_telemetry_t tm;
    unsigned points;
    assert_int_equal(run(&m, &tm, 200000u, &points), PROC_DONE);
    const uint8_t n = (uint8_t)fx.cfg.id_rs_levels;
    assert_int_equal(tm.phase, 4u * n + 2u);
    assert_int_equal(points, 4u * n + 2u); /* every phase seen, the report's too */
    /* R_s within 2 % (issue 25) */
    assert_true(fabsf(tm.result[0] / rs[c] - 1.0f) < 0.02f);
    /* the voltage error at the top level along alpha: 2/3 (e(i) + e(i/2))
     * (phase a carries i, b and c -i/2), within 5 % */
    const float i_top = tm.result[5];
    assert_true(fabsf(i_top - 0.9f * 8.0f) < 0.1f);
    const float truth = (2.0f / 3.0f) * (phase_err(&m, i_top) + phase_err(&m, 0.5f * i_top));
    assert_true(fabsf(tm.result[1] / truth - 1.0f) < 0.05f);
    /* the knee: at or above where the model's error becomes flat (i/2 on b, c) */
    assert_true(tm.result[2] >= 2.0f * m.knee * 0.99f && tm.result[2] <= i_top);
    /* the plateaus: odd */
    assert_true(fabsf(tm.result[3] + tm.result[4]) < 0.05f * fabsf(tm.result[3]));
    /* never above the limit */
    assert_true(m.i_peak <= 8.0f);
  }
}

static void a_single_level_would_not_separate(void **state) {
  (void)state;
  /* the broken-on-purpose check of the test's power: R = V / I at the top
   * level carries V0 / I (over 2 % here), the slope does not */
  fixture(0.5f, 1e-3f);
  model_t m = {0.5f, 1e-3f, 1e-3f, 0.4f, 0.6f, 0.02f, 0.01f, 0.0f, 0.0f, 7u, 0.0f, 0, {0.0f, 0.0f}};
  proc_telemetry_t tm;
  unsigned points;
  assert_int_equal(run(&m, &tm, 200000u, &points), PROC_DONE);
  const float r_single = (tm.result[0] * tm.result[5] + tm.result[1]) / tm.result[5];
  assert_true(fabsf(r_single / 0.5f - 1.0f) > 0.02f);
  assert_true(fabsf(tm.result[0] / 0.5f - 1.0f) < 0.02f);
}

/* The devices' resistance (the board's r_dev) is in the slope like the
 * winding's: R_s is the slope less r_dev, and the devices' drop goes to the
 * voltage error; an r_dev above the slope leaves no winding and fails. */
static void device_resistance_taken_out(void **state) {
  (void)state;
  const float rw = 0.05f, rdev = 0.02f; /* a low-resistance machine: r_dev 40 % of it */
  fixture(rw, 1e-4f);
  fx.cfg.r_dev = rdev;
  model_t m = {rw + rdev, 1e-4f, 1e-4f, 0.4f, 0.6f, 0.02f,       0.01f,
               0.0f,      0.0f,  99u,   0.0f, 0,    {0.0f, 0.0f}};
  proc_telemetry_t tm;
  unsigned points;
  assert_int_equal(run(&m, &tm, 200000u, &points), PROC_DONE);
  assert_true(fabsf(tm.result[0] / rw - 1.0f) < 0.02f);
  /* the error at the top level now holds the devices' drop r_dev i along alpha */
  const float i_top = tm.result[5];
  const float truth =
      (2.0f / 3.0f) * (phase_err(&m, i_top) + phase_err(&m, 0.5f * i_top)) + rdev * i_top;
  assert_true(fabsf(tm.result[1] / truth - 1.0f) < 0.05f);
  /* a board figure above the whole slope: no winding left */
  fixture(rw, 1e-4f);
  fx.cfg.r_dev = 2.0f * (rw + rdev);
  model_t m2 = {rw + rdev, 1e-4f, 1e-4f, 0.4f, 0.6f, 0.02f,       0.01f,
                0.0f,      0.0f,  99u,   0.0f, 0,    {0.0f, 0.0f}};
  assert_int_equal(run(&m2, &tm, 200000u, &points), PROC_FAILED);
  assert_int_equal(tm.fault, DRIVE_FAULT_CONTROL);
}

static void overcurrent_fails(void **state) {
  (void)state;
  fixture(0.5f, 1e-3f);
  const proc_row_t *row = proc_row(PROC_RS);
  row->init(&fx.st, &fx.su);
  proc_out_t out;
  const proc_in_t in = {&fx.s, {1.21f * 8.0f, 0.0f}, 24.0f, &fx.pos};
  assert_int_equal(row->step(&fx.st, &fx.su, &in, &out), PROC_FAILED);
  assert_int_equal(out.fault, DRIVE_FAULT_OVERCURRENT);
  row->init(&fx.st, &fx.su);
  const proc_in_t nan_in = {&fx.s, {NAN, 0.0f}, 24.0f, &fx.pos};
  assert_int_equal(row->step(&fx.st, &fx.su, &nan_in, &out), PROC_FAILED);
}

static void refuses_bad_levels_and_is_identification(void **state) {
  (void)state;
  fixture(0.5f, 1e-3f);
  const char *field = NULL;
  assert_null(proc_ident_refusal(PROC_RS, &fx.su, &field));
  fx.cfg.id_rs_levels = 2u;
  assert_non_null(proc_ident_refusal(PROC_RS, &fx.su, &field));
  assert_string_equal(field, "id_rs_levels");
  const proc_row_t *row = proc_row(PROC_RS);
  assert_int_equal(row->state, DRIVE_STATE_IDENT);
  assert_int_equal(row->caps, PROC_CAP_IDENT | PROC_CAP_GATES);
  assert_false(proc_applies(PROC_RS, &fx.su)); /* never in the start */
  assert_true(sizeof(proc_rs_t) <= 400u);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(resistance_and_voltage_error_separated),
      cmocka_unit_test(a_single_level_would_not_separate),
      cmocka_unit_test(device_resistance_taken_out),
      cmocka_unit_test(overcurrent_fails),
      cmocka_unit_test(refuses_bad_levels_and_is_identification),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
