/*
 * test_machine.c - the core machine model against hand-computed values and
 * brute-force MTPA. IPM: p = 4, Rs = 0.1, Ld = 1 mH, Lq = 2 mH,
 * lambda_m = 0.05 Vs.
 */
#include "core_test_util.h"

#include "model/machine.h"

static machine_t ipm(void) {
  machine_t m;
  assert_int_equal(machine_init_linear(&m, 4.0f, 0.1f, 1e-3f, 2e-3f, 0.05f), 0);
  return m;
}

static void test_init_rejects(void **state) {
  (void)state;
  machine_t m;
  assert_int_equal(machine_init_linear(&m, 0.0f, 0.1f, 1e-3f, 1e-3f, 0.1f), -1);
  assert_int_equal(machine_init_linear(&m, 2.0f, 0.0f, 1e-3f, 1e-3f, 0.1f), -1);
  assert_int_equal(machine_init_linear(&m, 2.0f, 0.1f, -1e-3f, 1e-3f, 0.1f), -1);
  assert_int_equal(machine_init_linear(&m, 2.0f, 0.1f, 1e-3f, 0.0f, 0.1f), -1);
  assert_int_equal(machine_init_linear(&m, 2.0f, 0.1f, 1e-3f, 1e-3f, -0.1f), -1);
  assert_int_equal(machine_init_linear(&m, 2.0f, 0.1f, NAN, 1e-3f, 0.1f), -1);
  assert_int_equal(machine_init_linear(&m, 2.0f, 0.1f, 1e-3f, 2e-3f, 0.0f), 0); /* SyR */
}

static void test_flux_current_inverse(void **state) {
  (void)state;
  const machine_t m = ipm();
  /* i = (-10, 20): lambda_d = -0.01 + 0.05 = 0.04, lambda_q = 0.04 */
  const dq_t l = machine_flux(&m, (dq_t){-10.0f, 20.0f});
  ASSERT_NEAR(l.d, 0.04, 1e-7);
  ASSERT_NEAR(l.q, 0.04, 1e-7);
  const dq_t i = machine_current(&m, l);
  ASSERT_NEAR(i.d, -10.0, 1e-4);
  ASSERT_NEAR(i.q, 20.0, 1e-4);
  const machine_ldq_t L = machine_inductance(&m, i);
  ASSERT_NEAR(L.dd, 1e-3f, 0.0);
  ASSERT_NEAR(L.qq, 2e-3f, 0.0);
  ASSERT_NEAR(L.dq, 0.0, 0.0);
  ASSERT_NEAR(L.qd, 0.0, 0.0);
  ASSERT_NEAR(machine_pm_flux(&m), 0.05f, 0.0);
  assert_false(machine_is_isotropic(&m, 0.1f));
}

static void test_torque(void **state) {
  (void)state;
  const machine_t m = ipm();
  /* 1.5 * 4 * (0.04 * 20 - 0.04 * (-10)) = 6 * 1.2 = 7.2 N m */
  ASSERT_NEAR(machine_torque(&m, (dq_t){-10.0f, 20.0f}), 7.2, 1e-5);
  ASSERT_NEAR(machine_torque(&m, (dq_t){0.0f, 10.0f}), 3.0, 1e-6);
  ASSERT_NEAR(machine_torque(&m, (dq_t){-10.0f, 0.0f}), 0.0, 1e-7);
}

/* The smallest current amplitude giving |t|, by a dense sweep of the
 * current angle at each amplitude (bisection on the amplitude). */
static double brute_mtpa_amp(const machine_t *m, double t) {
  double lo = 0.0, hi = 1e3;
  for (int it = 0; it < 60; ++it) {
    const double a = 0.5 * (lo + hi);
    double best = 0.0;
    for (int k = 0; k <= 20000; ++k) {
      const double beta = T_PI * (double)k / 20000.0; /* angle from +q towards -d */
      const dq_t i = {(float)(-a * sin(beta)), (float)(a * cos(beta))};
      const double tk = machine_torque(m, i);
      best = tk > best ? tk : best;
    }
    if (best >= t) {
      hi = a;
    } else {
      lo = a;
    }
  }
  return hi;
}

static void check_mtpa(const machine_t *m, float t) {
  const dq_t i = machine_mtpa_current(m, t);
  ASSERT_NEAR(machine_torque(m, i), t, 1e-4 * fabs(t) + 1e-6);
  const double amp = sqrt((double)i.d * i.d + (double)i.q * i.q);
  ASSERT_NEAR(amp, brute_mtpa_amp(m, fabs(t)), 2e-4 * amp + 1e-6);
  ASSERT_NEAR(machine_mtpa_torque(m, (float)amp), fabs(t), 1e-4 * fabs(t) + 1e-6);
}

static void test_mtpa_ipm(void **state) {
  (void)state;
  const machine_t m = ipm();
  for (float t = 0.05f; t < 60.0f; t *= 1.7f) {
    check_mtpa(&m, t);
  }
  const dq_t i = machine_mtpa_current(&m, -5.0f);
  ASSERT_NEAR(machine_torque(&m, i), -5.0, 1e-4);
  assert_true(i.d < 0.0f); /* d current negative for both signs of torque */
}

static void test_mtpa_spm_and_syr(void **state) {
  (void)state;
  machine_t spm;
  assert_int_equal(machine_init_linear(&spm, 21.0f, 7.1f, 0.057f, 0.057f, 0.19f), 0);
  const dq_t i = machine_mtpa_current(&spm, 20.0f);
  ASSERT_NEAR(i.d, 0.0, 0.0);
  ASSERT_NEAR(i.q, 20.0 / (1.5 * 21.0 * 0.19), 1e-5);
  assert_true(machine_is_isotropic(&spm, 1e-6f));

  machine_t syr; /* no magnet: MTPA at 45 degrees, i_d = -i_q */
  assert_int_equal(machine_init_linear(&syr, 2.0f, 6.8f, 0.05f, 0.25f, 0.0f), 0);
  for (float t = 0.1f; t < 20.0f; t *= 2.3f) {
    const dq_t s = machine_mtpa_current(&syr, t);
    ASSERT_NEAR(s.d, -s.q, 1e-5 * s.q);
    check_mtpa(&syr, t);
  }
  machine_t none; /* no magnet, no saliency: no torque at all */
  assert_int_equal(machine_init_linear(&none, 2.0f, 1.0f, 0.1f, 0.1f, 0.0f), 0);
  const dq_t z = machine_mtpa_current(&none, 3.0f);
  ASSERT_NEAR(z.d, 0.0, 0.0);
  ASSERT_NEAR(z.q, 0.0, 0.0);
  const machine_t m = ipm();
  const dq_t n = machine_mtpa_current(&m, NAN);
  ASSERT_NEAR(n.d, 0.0, 0.0);
  ASSERT_NEAR(n.q, 0.0, 0.0);
}

static void test_voltage_ss(void **state) {
  (void)state;
  const machine_t m = ipm();
  /* we = 100: vd = 0.1*(-10) - 100*0.04 = -5, vq = 0.1*20 + 100*0.04 = 6 */
  const dq_t v = machine_voltage_ss(&m, (dq_t){-10.0f, 20.0f}, 100.0f);
  ASSERT_NEAR(v.d, -5.0, 1e-5);
  ASSERT_NEAR(v.q, 6.0, 1e-5);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_init_rejects),     cmocka_unit_test(test_flux_current_inverse),
      cmocka_unit_test(test_torque),           cmocka_unit_test(test_mtpa_ipm),
      cmocka_unit_test(test_mtpa_spm_and_syr), cmocka_unit_test(test_voltage_ss),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
