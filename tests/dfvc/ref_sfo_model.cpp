/*
 * ref_sfo_model.cpp - Eigen (double) reference of the stator-flux-frame
 * model of the decoupled DFVC (model/sfo_model.h, Varatharajan 2022),
 * written independently with Eigen's 2x2 algebra:
 *   (6)  lambda^a = J lambda - L J i         (7)  (lambda^a)^T J i
 *   (9)  i^a = J i - L^-1 J lambda           (10) lambda^T J i^a
 *   (22) a = u_tau^T L^-1 u_f (the (tau, f) element of e^{-J delta} L^-1
 *        e^{J delta}, eq. (20)), b = lambda^T J i^a / |lambda|^2
 *   (17) a', b' in the fluxdrive frame (PM on +d) from the apparent
 *        inductances, by differentiating i_tau(lambda, delta) of (15)
 *        numerically (central differences in long double)
 *   (23) T = [1 0; -a/b 1/b] as a matrix, and its inverse
 * over a long pseudo-random sequence of positive-definite incremental
 * inductance matrices, fluxes and currents; the float core within float
 * rounding of the scale of each quantity.
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

#include "model/sfo_model.h"
}

namespace {

using V = Eigen::Vector2d;
using M = Eigen::Matrix2d;

const M J = (M() << 0.0, -1.0, 1.0, 0.0).finished();

V v_of(dq_t x) {
  return V(x.d, x.q);
}

/* i_tau of (15) in the fluxdrive frame for flux amplitude lam and load
 * angle d (from the PM axis) with constant apparent inductances */
long double itau_of(long double lam, long double d, long double ld, long double lq,
                    long double lm) {
  const long double id = (lam * std::cos(d) - lm) / ld;
  const long double iq = lam * std::sin(d) / lq;
  return -id * std::sin(d) + iq * std::cos(d);
}

void test_against_eigen(void **state) {
  (void)state;
  std::mt19937 rng(20221);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double pi = 3.14159265358979323846;
  double w_la = 0, w_ia = 0, w_ca = 0, w_cv = 0, w_a = 0, w_b = 0, w_as = 0, w_bs = 0, w_t = 0,
         w_ang = 0;
  const int n = 200000;
  for (int k = 0; k < n; ++k) {
    /* positive definite L: l_dd, l_qq in [0.01, 1] H, |l_dq| < 0.3 sqrt(l_dd l_qq) */
    const float ldd = static_cast<float>(0.01 + 0.99 * u01(rng));
    const float lqq = static_cast<float>(0.01 + 0.99 * u01(rng));
    const float lx =
        static_cast<float>((2.0 * u01(rng) - 1.0) * 0.3 * std::sqrt(double(ldd) * double(lqq)));
    const machine_ldq_t lf = {ldd, lx, lx, lqq};
    const double la = 0.05 + 1.45 * u01(rng), ta = 2 * pi * u01(rng);
    const double ia = 8.0 * u01(rng), ti = 2 * pi * u01(rng);
    const dq_t lam = {static_cast<float>(la * std::cos(ta)), static_cast<float>(la * std::sin(ta))};
    const dq_t cur = {static_cast<float>(ia * std::cos(ti)), static_cast<float>(ia * std::sin(ti))};
    const V l = v_of(lam), i = v_of(cur);
    M L;
    L << ldd, lx, lx, lqq;
    const M Li = L.inverse();
    const double lmin = std::min(double(ldd), double(lqq));

    /* (6), (7) */
    const V la_ref = J * l - L * J * i;
    const V la_c = v_of(sfo_aux_flux(lam, cur, lf));
    const double s_la = l.norm() + L.norm() * i.norm();
    w_la = std::max(w_la, (la_c - la_ref).norm() / s_la);
    w_ca = std::max(w_ca,
                    std::fabs(sfo_mtpa_cross(sfo_aux_flux(lam, cur, lf), cur) - la_ref.dot(J * i)) /
                        (s_la * (i.norm() + 1e-3)));
    /* (9), (10) */
    const V ia_ref = J * i - Li * J * l;
    const dq_t ia_f = sfo_aux_current(lam, cur, lf);
    const V ia_c = v_of(ia_f);
    const double s_ia = i.norm() + l.norm() / lmin;
    w_ia = std::max(w_ia, (ia_c - ia_ref).norm() / s_ia);
    w_cv = std::max(w_cv,
                    std::fabs(sfo_mtpv_cross(lam, ia_f) - l.dot(J * ia_ref)) / (l.norm() * s_ia));
    /* (22) */
    const V uf = l / l.norm(), ut = J * uf;
    const double a_ref = ut.dot(Li * uf);
    const double b_ref = l.dot(J * ia_ref) / l.squaredNorm();
    const sfo_gains_t g = sfo_gains(lam, cur, lf);
    w_a = std::max(w_a, std::fabs(g.a - a_ref) / (1.0 / lmin));
    w_b = std::max(w_b, std::fabs(g.b - b_ref) / (s_ia / l.norm()));
    /* line angle between lambda and i^a, in [0, pi/2] */
    double ang = std::acos(std::min(1.0, std::fabs(l.dot(ia_ref)) / (l.norm() * ia_ref.norm())));
    if (ia_ref.norm() > 1e-3) {
      w_ang = std::max(w_ang, std::fabs(sfo_line_angle(lam, ia_f) - ang));
    }
    /* (23) as a matrix, and back (21) */
    if (std::fabs(b_ref) > 0.1 / lmin) {
      M T;
      T << 1.0, 0.0, -g.a / g.b, 1.0 / g.b;
      const dq_t x = {static_cast<float>(2.0 * u01(rng) - 1.0),
                      static_cast<float>(2.0 * u01(rng) - 1.0)};
      const V y = T * v_of(x);
      const V yc = v_of(sfo_transform(g, x));
      w_t = std::max(w_t, (yc - y).norm() / (1.0 + std::fabs(g.a / g.b)));
      const V back = v_of(sfo_transform_inv(g, sfo_transform(g, x)));
      w_t = std::max(w_t, (back - v_of(x)).norm() / (1.0 + std::fabs(g.a)));
    }
    /* (17): apparent inductances 0.02..0.5 H, PM flux 0..0.3 Vs */
    if (k % 20 == 0) {
      const long double lad = 0.02 + 0.48 * u01(rng), laq = 0.02 + 0.48 * u01(rng);
      const long double lm = 0.3 * u01(rng);
      const long double lam_a = 0.1 + 1.4 * u01(rng), d = pi * (2 * u01(rng) - 1);
      const long double h = 1e-6L;
      const long double a_n =
          (itau_of(lam_a + h, d, lad, laq, lm) - itau_of(lam_a - h, d, lad, laq, lm)) / (2 * h);
      const long double b_n =
          (itau_of(lam_a, d + h, lad, laq, lm) - itau_of(lam_a, d - h, lad, laq, lm)) /
          (2 * h * lam_a);
      const sincos_t sc = {static_cast<float>(std::sin(double(d))),
                           static_cast<float>(std::cos(double(d)))};
      const sfo_gains_t s = sfo_gains_sota(static_cast<float>(lam_a), sc, static_cast<float>(lad),
                                           static_cast<float>(laq), static_cast<float>(lm));
      const double sc_ab = 1.0 / double(std::min(lad, laq)) + double(lm / (lam_a * lad));
      w_as = std::max(w_as, std::fabs(s.a - double(a_n)) / sc_ab);
      w_bs = std::max(w_bs, std::fabs(s.b - double(b_n)) / sc_ab);
    }
  }
  std::printf("sfo_model vs Eigen over %d cases (relative to each scale): lambda^a %.2g, "
              "(7) %.2g, i^a %.2g, (10) %.2g, a %.2g, b %.2g, a' %.2g, b' %.2g, T %.2g, "
              "line angle %.2g rad\n",
              n, w_la, w_ca, w_ia, w_cv, w_a, w_b, w_as, w_bs, w_t, w_ang);
  /* float rounding: a few ulp (1.2e-7) of each scale; measured 0.9 .. 3.5e-7
   * (the angle: fd_atan2f's 2e-6 and the rounding of small |i^a|) */
  assert_true(w_la < 2e-6);
  assert_true(w_ca < 2e-6);
  assert_true(w_ia < 2e-6);
  assert_true(w_cv < 2e-6);
  assert_true(w_a < 2e-6);
  assert_true(w_b < 2e-6);
  assert_true(w_as < 2e-6);
  assert_true(w_bs < 2e-6);
  assert_true(w_t < 2e-6);
  assert_true(w_ang < 1e-4);
}

} // namespace

int main() {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_against_eigen)};
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
