/*
 * test_deadtime_comp.c - predictive dead-time compensation, Rubino 2020,
 * Fig. 8: td/Ts times a saturated-linear sign of the predicted current,
 * duties clamped to [0, 1].
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>

#include "control/deadtime_comp.h"

static void test_apply(void **state) {
  (void)state;
  deadtime_comp_t d;
  const deadtime_comp_cfg_t cfg = {1e-6f, 62.5e-6f, 0.1f};
  assert_int_equal(deadtime_comp_init(&d, &cfg), 0);
  const float r = 1e-6f / 62.5e-6f; /* 0.016 */
  const float in[3] = {0.5f, 0.995f, 0.004f};
  float out[3];
  deadtime_comp_apply(&d, in, (abc_t){2.0f, 0.05f, -1.0f}, out);
  assert_true(fabsf(out[0] - (0.5f + r)) < 1e-7f);
  assert_true(fabsf(out[1] - 1.0f) < 1e-7f); /* 0.995 + 0.5 r = 1.003 -> clamped */
  assert_true(fabsf(out[2] - 0.0f) < 1e-7f); /* 0.004 - r -> clamped */
  deadtime_comp_apply(&d, in, (abc_t){-0.05f, -0.2f, 0.0f}, out);
  assert_true(fabsf(out[0] - (0.5f - 0.5f * r)) < 1e-7f);
  assert_true(fabsf(out[2] - 0.004f) < 1e-7f);
  /* in-place */
  float io[3] = {0.3f, 0.3f, 0.3f};
  deadtime_comp_apply(&d, io, (abc_t){1.0f, -1.0f, NAN}, io);
  assert_true(fabsf(io[0] - (0.3f + r)) < 1e-7f && fabsf(io[1] - (0.3f - r)) < 1e-7f &&
              fabsf(io[2] - 0.3f) < 1e-7f);
}

static void test_sign_and_cfg(void **state) {
  (void)state;
  deadtime_comp_t d;
  deadtime_comp_cfg_t cfg = {1e-6f, 62.5e-6f, 0.0f};
  assert_int_equal(deadtime_comp_init(&d, &cfg), 0);
  assert_true(fabsf(deadtime_comp_sign(&d, 1e-3f) - 1.0f) < 1e-7f);
  assert_true(fabsf(deadtime_comp_sign(&d, -1e-3f) + 1.0f) < 1e-7f);
  assert_true(fabsf(deadtime_comp_sign(&d, 0.0f)) < 1e-7f);
  cfg.i_band = 0.2f;
  assert_int_equal(deadtime_comp_init(&d, &cfg), 0);
  assert_true(fabsf(deadtime_comp_sign(&d, 0.05f) - 0.25f) < 1e-6f);
  assert_true(fabsf(deadtime_comp_sign(&d, -0.3f) + 1.0f) < 1e-7f);
  cfg.td = 70e-6f;
  assert_int_equal(deadtime_comp_init(&d, &cfg), -1);
  cfg.td = 1e-6f;
  cfg.i_band = -1.0f;
  assert_int_equal(deadtime_comp_init(&d, &cfg), -1);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_apply),
      cmocka_unit_test(test_sign_and_cfg),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
