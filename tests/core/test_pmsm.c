/*
 * test_pmsm.c - linear PMSM model against hand-computed values.
 * p = 4, Rs = 0.1, Ld = 1 mH, Lq = 2 mH, lambda_m = 0.05 Vs.
 */
#include "core_test_util.h"

#include "model/pmsm.h"

static const pmsm_params_t M = {4.0f, 0.1f, 1e-3f, 2e-3f, 0.05f};

static void test_flux(void **state) {
  (void)state;
  /* i = (-10, 20): lambda_d = -0.01 + 0.05 = 0.04, lambda_q = 0.04 */
  const dq_t l = pmsm_flux(&M, (dq_t){-10.0f, 20.0f});
  ASSERT_NEAR(l.d, 0.04, 1e-7);
  ASSERT_NEAR(l.q, 0.04, 1e-7);
}

static void test_torque(void **state) {
  (void)state;
  /* 1.5 * 4 * (0.04 * 20 - 0.04 * (-10)) = 6 * 1.2 = 7.2 N m */
  ASSERT_NEAR(pmsm_torque(&M, (dq_t){-10.0f, 20.0f}), 7.2, 1e-5);
  /* id = 0: 1.5 * 4 * 0.05 * 10 = 3 N m */
  ASSERT_NEAR(pmsm_torque(&M, (dq_t){0.0f, 10.0f}), 3.0, 1e-6);
  /* no q current: neither magnet nor reluctance torque */
  ASSERT_NEAR(pmsm_torque(&M, (dq_t){-10.0f, 0.0f}), 0.0, 1e-7);
}

static void test_iq_for_torque(void **state) {
  (void)state;
  ASSERT_NEAR(pmsm_iq_for_torque(&M, 3.0f), 10.0, 1e-5); /* 3 / 0.3 */
  ASSERT_NEAR(pmsm_iq_for_torque(&M, -1.5f), -5.0, 1e-5);
  for (int k = -5; k <= 5; k++) {
    const float t = 2.3f * (float)k;
    ASSERT_NEAR(pmsm_torque(&M, (dq_t){0.0f, pmsm_iq_for_torque(&M, t)}), t, 1e-5);
  }
  const pmsm_params_t syr = {2.0f, 0.1f, 1e-3f, 2e-3f, 0.0f};
  ASSERT_NEAR(pmsm_iq_for_torque(&syr, 3.0f), 0.0, 0.0); /* no magnet: defined 0 */
  ASSERT_NEAR(pmsm_iq_for_torque(&M, NAN), 0.0, 0.0);
}

static void test_voltage_ss(void **state) {
  (void)state;
  /* we = 100: vd = 0.1*(-10) - 100*0.04 = -5, vq = 0.1*20 + 100*0.04 = 6 */
  const dq_t v = pmsm_voltage_ss(&M, (dq_t){-10.0f, 20.0f}, 100.0f);
  ASSERT_NEAR(v.d, -5.0, 1e-5);
  ASSERT_NEAR(v.q, 6.0, 1e-5);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_flux),
      cmocka_unit_test(test_torque),
      cmocka_unit_test(test_iq_for_torque),
      cmocka_unit_test(test_voltage_ss),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
