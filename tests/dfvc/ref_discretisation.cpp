/*
 * ref_discretisation.cpp - Eigen (double) reference for Rubino 2020,
 * eqs. (10)-(15) and (21): the discretisation by the matrix exponential of
 * the augmented continuous system [[A, b], [0, 0]] in a frame rotating at
 * omega_xy (rotor frame for omega_xy = omega_r, alpha-beta for 0), and the
 * MPE by the exponential of the (alpha, beta) system augmented with the held
 * voltage and the PM flux vector (rotating: exact form; held: printed (21)).
 * Compared with the float core within float rounding.
 */
#include <cmath>
#include <cstdio>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "estimation/current_predictor.h"
#include "model/spm_discrete.h"
}

namespace {

const double kRs = 7.1, kLs = 0.057, kLm = 0.19, kTs = 62.5e-6, kP = 21.0;

double rpm_to_we(double rpm) {
  return rpm / 60.0 * 2.0 * M_PI * kP;
}

void check(double got, double want, double tol, const char *what) {
  if (std::fabs(got - want) > tol) {
    fail_msg("%s: got %.10g want %.10g (|err| %.3g > %.3g)", what, got, want, std::fabs(got - want),
             tol);
  }
}

/* Eqs. (11)-(15) vs expm of [[A Ts, b Ts], [0, 0]]. */
void test_discretisation(void **) {
  spm_discrete_t m;
  assert_int_equal(spm_discrete_init(&m, (float)kRs, (float)kLs, (float)kTs), 0);
  const double ws[5] = {0.0, rpm_to_we(100.0), rpm_to_we(-450.0), rpm_to_we(1200.0),
                        rpm_to_we(3000.0)};
  for (double w : ws) {
    Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
    M(0, 0) = -kRs / kLs;
    M(0, 1) = w;
    M(1, 0) = -w;
    M(1, 1) = -kRs / kLs;
    M(0, 2) = 1.0 / kLs;
    M(1, 3) = 1.0 / kLs;
    const Eigen::Matrix4d E = (M * kTs).exp();
    const Eigen::Matrix2d Ad = E.block<2, 2>(0, 0);
    const Eigen::Matrix2d bd = E.block<2, 2>(0, 2);
    const spm_discrete_coef_t c = spm_discrete_coef(&m, (float)w);
    std::printf("  w = %8.1f: a_xx %.9f/%.9f a_xy %.3e/%.3e b_xx %.6e/%.6e b_xy %.4e/%.4e\n", w,
                c.a_xx, Ad(0, 0), c.a_xy, Ad(0, 1), c.b_xx, bd(0, 0), c.b_xy, bd(0, 1));
    /* structure of (13) */
    check(Ad(1, 1), Ad(0, 0), 1e-14, "Ad symmetric diag");
    check(Ad(1, 0), -Ad(0, 1), 1e-14, "Ad skew");
    check(bd(1, 0), -bd(0, 1), 1e-14, "bd skew");
    /* float core vs double reference: relative 1e-6 of the largest entry */
    check(c.a_xx, Ad(0, 0), 2e-7, "a_xx");
    check(c.a_xy, Ad(0, 1), 2e-7, "a_xy");
    check(c.b_xx, bd(0, 0), 2e-6 * bd(0, 0), "b_xx");
    check(c.b_xy, bd(0, 1), 2e-6 * bd(0, 0), "b_xy");
  }
}

/* MPE: x = [i; v; lambda_m_ab], di/dt = -f i + (v - w J lambda_m)/L, dv/dt = 0,
 * d lambda_m/dt = w J lambda_m (exact) or 0 (printed (21)). */
void check_predictor(current_predictor_mode_t mode) {
  static machine_t machine; /* the predictor holds a pointer to it */
  assert_int_equal(
      machine_init_linear(&machine, 21.0f, (float)kRs, (float)kLs, (float)kLs, (float)kLm), 0);
  current_predictor_t p;
  const current_predictor_cfg_t cfg = {&machine, (float)kTs, mode};
  assert_int_equal(current_predictor_init(&p, &cfg), 0);
  Eigen::Matrix2d J;
  J << 0.0, -1.0, 1.0, 0.0;
  const double rpm[4] = {0.0, 100.0, -700.0, 1200.0};
  double worst = 0.0;
  for (double r : rpm) {
    const double w = rpm_to_we(r);
    Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
    M.block<2, 2>(0, 0) = -kRs / kLs * Eigen::Matrix2d::Identity();
    M.block<2, 2>(0, 2) = Eigen::Matrix2d::Identity() / kLs;
    M.block<2, 2>(0, 4) = -w * J / kLs;
    if (mode == CURRENT_PREDICTOR_EXACT) {
      M.block<2, 2>(4, 4) = w * J;
    }
    const Eigen::Matrix<double, 6, 6> E = (M * kTs).exp();
    for (int n = 0; n < 16; ++n) {
      const double th = -3.0 + 0.39 * n;
      Eigen::Matrix<double, 6, 1> x;
      x << 2.5 * std::cos(0.7 * n), 2.5 * std::sin(0.7 * n), 160.0 * std::cos(1.0 - 0.5 * n),
          160.0 * std::sin(1.0 - 0.5 * n), kLm * std::cos(th), kLm * std::sin(th);
      const Eigen::Matrix<double, 6, 1> y = E * x;
      const ab_t got = current_predictor_step(&p, ab_t{(float)x(0), (float)x(1)},
                                              ab_t{(float)x(2), (float)x(3)}, (float)th, (float)w);
      const double e = std::hypot(got.alpha - y(0), got.beta - y(1));
      worst = e > worst ? e : worst;
    }
  }
  std::printf("  MPE %s vs Eigen expm: worst |error| %.3g A\n",
              mode == CURRENT_PREDICTOR_EXACT ? "exact" : "eq. (21)", worst);
  assert_true(worst < 5e-6);
}

void test_predictor_exact(void **) {
  check_predictor(CURRENT_PREDICTOR_EXACT);
}
void test_predictor_eq21(void **) {
  check_predictor(CURRENT_PREDICTOR_EQ21);
}

} // namespace

int main() {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_discretisation),
      cmocka_unit_test(test_predictor_exact),
      cmocka_unit_test(test_predictor_eq21),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
