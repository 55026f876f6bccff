/*
 * The star point's a, b identification (proc_star.c) without the SIL: its
 * check refuses a setup without star-point samples by name (pos_source);
 * on signals made from (3.6) exactly, the rotor a constant lag behind the
 * vector, it finds a and b within 0.1 % (the bins' averaging divided out),
 * with either sign of a (the vector decides it) and |p| up to 0.45; without
 * star-point samples it fails with the position fault; its current stays
 * the test current's.
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

#define PI_F 3.14159265f

typedef struct {
  PROC_FIXTURE_FIELDS
  pos_estimate_t pos;
} fixture_t;

static fixture_t fx;

static void fixture(pos_source_t src) {
  memset(&fx, 0, sizeof fx);
  drive_config_default(&fx.cfg);
  fx.cfg.pos_source = src;
  proc_fixture_bind(&fx);
  fx.s.valid = true;
  fx.s.v_dc = 24.0f;
}

static void refused_without_star_point(void **state) {
  (void)state;
  fixture(POS_SOURCE_ENCODER);
  const char *field = NULL;
  assert_non_null(proc_star.check(&fx.su, &field));
  assert_string_equal(field, "pos_source");
  assert_non_null(proc_ident_refusal(PROC_STAR, &fx.su, &field));
  fixture(POS_SOURCE_DFC);
  field = NULL;
  assert_null(proc_star.check(&fx.su, &field));
  assert_null(proc_ident_refusal(PROC_STAR, &fx.su, &field));
  assert_true((proc_star.caps & PROC_CAP_IDENT) != 0u);
  assert_true(sizeof(proc_star_t) <= 480u); /* well under the union's 1 KiB */
}

/* The vector's angle the procedure asks in its state's period (proc_star.c:
 * the alignment at 0, the sweeps to dir pi and back, the fits held). */
static float vector_angle(const proc_star_t *t, uint32_t n_sweep) {
  const float f = (float)t->n / (float)n_sweep;
  switch (t->phase) {
  case 1:
    return t->dir * PI_F * f;
  case 2:
    return t->dir * PI_F;
  case 3:
    return t->dir * PI_F * (1.0f - f);
  default:
    return 0.0f;
  }
}

/* Runs the procedure on (3.6) with the rotor lag rad (electrical) behind
 * the vector; returns its end status, *tm its telemetry. */
static int run_on_model(float a, float b, float lag, bool star, proc_telemetry_t *tm) {
  fixture(POS_SOURCE_DFC);
  proc_star.init(&fx.st, &fx.su);
  const uint32_t n_sweep = (uint32_t)(fx.cfg.id_star_time / fx.cfg.ts) + 1u;
  const float i_test = fx.cfg.id_star_current * fx.cfg.i_max;
  int res = PROC_RUNNING;
  for (uint32_t k = 0; k < 40u * n_sweep && res == PROC_RUNNING; ++k) {
    const proc_star_t *t = &fx.st.star;
    const float phi = vector_angle(t, n_sweep);
    const float th = phi - (t->phase == 3 ? -t->dir : t->dir) * lag;
    /* (3.6): Gamma_alpha, Gamma_beta, and the component of leg x */
    const float ga = -a * cosf(2.0f * th) + b * cosf(4.0f * th);
    const float gb = a * sinf(2.0f * th) + b * sinf(4.0f * th);
    const unsigned x = k % 3u;
    const float gx = x == 0u   ? ga
                     : x == 1u ? -0.5f * ga + 0.8660254f * gb
                               : -0.5f * ga - 0.8660254f * gb;
    fx.s.n_star = star ? 2u : 0u;
    fx.s.test_vector = (uint8_t)(2u * x + 1u);
    fx.s.v_star[0] = -12.0f;
    fx.s.v_star[1] = -12.0f + fx.s.v_dc * (gx + 1.0f / 3.0f);
    /* the current loop's plant: the current follows the vector */
    const proc_in_t in = {&fx.s, {i_test * cosf(phi), i_test * sinf(phi)}, 10.0f, &fx.pos};
    proc_out_t out;
    res = proc_star.step(&fx.st, &fx.su, &in, &out);
    proc_star.publish(&fx.st, tm);
    if (res == PROC_FAILED) {
      tm->fault = out.fault;
    }
  }
  return res;
}

static void finds_a_b_of_the_model(void **state) {
  (void)state;
  static const float cases[][3] = {
      {0.05f, -0.00466f, 0.1f}, /* Table 5.1 */
      {-0.1f, -0.03f, 0.2f},    /* a < 0 (drawn star seeds 1-3), p +0.3 */
      {0.2f, 0.09f, 0.0f},      /* p 0.45 */
      {-0.12f, 0.0486f, 0.3f},  /* drawn star seed 1: p -0.4 */
  };
  for (unsigned c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    proc_telemetry_t tm;
    memset(&tm, 0, sizeof tm);
    const float a = cases[c][0], b = cases[c][1];
    assert_int_equal(run_on_model(a, b, cases[c][2], true, &tm), PROC_DONE);
    assert_true(fabsf(tm.result[0] / a - 1.0f) < 1e-3f);
    assert_true(fabsf(tm.result[1] / b - 1.0f) < 1e-3f);
    assert_true(fabsf(tm.result[2] / (b / a) - 1.0f) < 2e-3f);
    assert_true(tm.result[4] < 1e-3f);                                       /* the residual */
    assert_true(fabsf(tm.result[5]) < 1e-3f && fabsf(tm.result[6]) < 1e-3f); /* the sweeps */
    assert_true(fabsf(fabsf(tm.result[7]) - cases[c][2]) < 0.02f);           /* the lag */
    assert_int_equal(tm.phase, 4);
  }
}

static void fails_without_star_samples(void **state) {
  (void)state;
  proc_telemetry_t tm;
  memset(&tm, 0, sizeof tm);
  assert_int_equal(run_on_model(0.05f, -0.0047f, 0.1f, false, &tm), PROC_FAILED);
  assert_int_equal(tm.fault, DRIVE_FAULT_POSITION);
  assert_int_equal(tm.phase, 1); /* at the first bin's end */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(refused_without_star_point),
      cmocka_unit_test(finds_a_b_of_the_model),
      cmocka_unit_test(fails_without_star_samples),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
