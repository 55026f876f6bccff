/*
 * ref_rls_ab.cpp - Eigen (double) reference of the RLS of the DFC
 * amplitudes (estimation/rls_ab.h, Fabbri 2022 (4.54)-(4.57) with a
 * forgetting factor): K = P H^T (H P H^T + R)^-1 by Eigen's inverse, x +=
 * K (Gamma - H x), P = (P - K H P) / lambda, over random angles, speeds
 * and noisy signals; limits set wide so that they do not act. Every other
 * run carries a sequentiality map K (dfc_vec_t.k, random near the
 * identity): the b column of H is then M (cos 4theta, sin 4theta) with
 * M = [k0 -k1; -k2 k3] (C K C undone), the signals built the same way.
 * The float version within the stated bounds.
 */
#include <cmath>
#include <cstdio>
#include <random>

#include <Eigen/Dense>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "estimation/rls_ab.h"
}

namespace {

void test_against_eigen(void **state) {
  (void)state;
  std::mt19937 rng(4257);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  double w_x = 0.0, w_p = 0.0;
  for (int run = 0; run < 20; ++run) {
    const double a = 0.02 + 0.08 * u01(rng), b = (u01(rng) - 0.5) * 0.8 * a;
    const double sigma = 1e-4 + 1e-3 * u01(rng), lambda = 0.999 + 0.0009 * u01(rng);
    const rls_ab_cfg_t c = {static_cast<float>(lambda), static_cast<float>(sigma * sigma), 1e-20f,
                            1e3f};
    rls_ab_t k;
    assert_true(rls_ab_init(&k, &c));
    const double p0 = 1e-3;
    rls_ab_reset(&k, static_cast<float>(0.7 * a), static_cast<float>(1.3 * b),
                 static_cast<float>(p0));
    Eigen::Vector2d x(0.7 * a, 1.3 * b);
    Eigen::Matrix2d P = p0 * Eigen::Matrix2d::Identity();
    const Eigen::Matrix2d R = sigma * sigma * Eigen::Matrix2d::Identity();
    float km[4] = {1.0f, 0.0f, 0.0f, 1.0f};
    if (run % 2 == 1) {
      for (float &v : km) {
        v += static_cast<float>(0.2 * (u01(rng) - 0.5));
      }
    }
    Eigen::Matrix2d M;
    M << km[0], -km[1], -km[2], km[3];
    double th = 6.28 * u01(rng);
    const double dth = 0.002 + 0.05 * u01(rng);
    for (int n = 0; n < 20000; ++n) {
      th += dth;
      const Eigen::Vector2d h4 = M * Eigen::Vector2d(std::cos(4 * th), std::sin(4 * th));
      const double ga = -a * std::cos(2 * th) + b * h4(0) + sigma * n01(rng);
      const double gb = a * std::sin(2 * th) + b * h4(1) + sigma * n01(rng);
      const float c2 = static_cast<float>(std::cos(2 * th)),
                  s2 = static_cast<float>(std::sin(2 * th));
      assert_true(rls_ab_update(&k, static_cast<float>(ga), static_cast<float>(gb), c2, s2,
                                run % 2 == 1 ? km : nullptr));
      Eigen::Matrix2d H;
      H << -std::cos(2 * th), h4(0), std::sin(2 * th), h4(1);
      const Eigen::Matrix2d K = P * H.transpose() * (H * P * H.transpose() + R).inverse();
      x += K * (Eigen::Vector2d(ga, gb) - H * x);
      P = (P - K * H * P) / lambda;
      w_x = std::max(w_x, std::max(std::abs(k.x[0] - x(0)), std::abs(k.x[1] - x(1))) / a);
      w_p = std::max(w_p, std::abs(k.p[0] - P(0, 0)) / P(0, 0));
    }
  }
  std::printf("ref_rls_ab: 20 runs x 20000 updates: a, b %.2e of a, P11 %.2e (relative)\n", w_x,
              w_p);
  assert_true(w_x < 1e-3);
  assert_true(w_p < 1e-2);
}

} // namespace

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_against_eigen)};
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
