/*
 * ref_dfc.cpp - Eigen (double) reference of the star-point position
 * (estimation/dfc.h, Fabbri 2022), written independently:
 *   signals   Gamma_x = (v_after - v_before) / v_dc - 1/3       (2.101)
 *   vector    the least-squares solution z of Re(conj(d_x) z) = Gamma_x,
 *             d_x = c_x e^{-j phi_x}, phi_x = 2 omega_e (t_new - t_x), with
 *             Eigen's QR on the 3x2 system and exact rotations (libm), and
 *             K = argmin over the projections on e_x = c_x e^{+j2phi_x}
 *   IVD       (3.100) with K: 2theta_k = angle(zeta + p conj(K e^{j(4theta_{k-1}
 *             + phi_b)}) ... ) - phi_a, as complex doubles, then one atan2
 * over a long pseudo-random sequence of angles, anisotropies, phase shifts,
 * speeds and component orders; the float core (its series rotations, unit
 * vectors and the Q31 CORDIC) within the stated bounds.
 */
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>

#include <Eigen/Dense>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "estimation/dfc.h"
#include "math/cordic_q31.h"
}

namespace {

using C = std::complex<double>;
const double PI = 3.14159265358979323846;

double wrap(double x) {
  return std::remainder(x, 2.0 * PI);
}

/* Gamma / v_dc of (3.97) at angle th */
C model(double a, double b, double th, double pa, double pb) {
  return C(-a * std::cos(2 * th + pa) + b * std::cos(4 * th + pb),
           a * std::sin(2 * th + pa) + b * std::sin(4 * th + pb));
}

void test_against_eigen(void **state) {
  (void)state;
  std::mt19937 rng(2022);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const C cx[3] = {C(1, 0), C(-0.5, std::sqrt(3.0) / 2), C(-0.5, -std::sqrt(3.0) / 2)};
  double w_vec = 0, w_k = 0, w_ang = 0, w_sig = 0;
  const int n_cases = 100000;
  for (int n = 0; n < n_cases; ++n) {
    const double a = 0.01 + 0.1 * u01(rng), p = -0.45 + 0.9 * u01(rng), b = p * a;
    const double pa = 0.2 * (u01(rng) - 0.5), pb = 0.4 * (u01(rng) - 0.5);
    const double th = 2 * PI * u01(rng), ts = 62.5e-6;
    const double we = 2 * PI * (u01(rng) - 0.5) * 8 * 1500 / 60.0; /* +-1500 rpm, 8 pp */
    const int first = static_cast<int>(3 * u01(rng)) % 3;
    const unsigned iters = static_cast<unsigned>(1 + 7 * u01(rng));
    /* three components at three instants, newest last */
    dfc_signals_t s;
    dfc_signals_reset(&s);
    double gam[3], tx[3];
    for (int k = 0; k < 3; ++k) {
      const int x = (first + k) % 3;
      tx[x] = ts * k;
      const double thk = th - we * ts * (2 - k);
      gam[x] = std::real(std::conj(cx[x]) * model(a, b, thk, pa, pb));
      const double vdc = 12.0 + 36.0 * u01(rng), vb = -0.5 * vdc;
      const float va = static_cast<float>(vb + vdc * (gam[x] + 1.0 / 3.0));
      assert_true(dfc_signals_push(&s, static_cast<uint8_t>(2 * x + 1), static_cast<float>(vb), va,
                                   static_cast<float>(vdc), static_cast<float>(tx[x])));
      w_sig = std::max(w_sig, std::abs(static_cast<double>(s.g[x]) - gam[x]) / a);
    }
    /* the reference vector and K */
    Eigen::Matrix<double, 3, 2> D, E;
    Eigen::Vector3d g;
    for (int x = 0; x < 3; ++x) {
      const double phi = 2 * we * (tx[(first + 2) % 3] - tx[x]);
      const C d = cx[x] * std::exp(C(0, -phi)), e = cx[x] * std::exp(C(0, 2 * phi));
      D(x, 0) = d.real();
      D(x, 1) = d.imag();
      E(x, 0) = e.real();
      E(x, 1) = e.imag();
      g(x) = gam[x];
    }
    const Eigen::Vector2d z = D.colPivHouseholderQr().solve(g);
    const Eigen::Matrix2d K = (D.transpose() * D).inverse() * (D.transpose() * E);
    dfc_vec_t v;
    dfc_signals_vector(&s, static_cast<float>(2 * we), &v);
    w_vec = std::max(w_vec, std::max(std::abs(v.al - z(0)), std::abs(v.be - z(1))) / a);
    const double kc[4] = {K(0, 0), -K(0, 1), -K(1, 0), K(1, 1)}; /* C K C */
    for (int i = 0; i < 4; ++i) {
      w_k = std::max(w_k, std::abs(static_cast<double>(v.k[i]) - kc[i]));
    }
    /* (3.100) with K in complex doubles */
    const C zeta = -std::conj(C(z(0), z(1))) / a;
    double t2 = std::arg(zeta) - pa;
    for (unsigned k = 1; k <= iters; ++k) {
      const C q = std::exp(C(0, -(2 * t2 + pb)));
      const C kq(kc[0] * q.real() + kc[1] * q.imag(), kc[2] * q.real() + kc[3] * q.imag());
      t2 = std::arg(zeta + p * kq) - pa;
    }
    const dfc_cfg_t c = {DFC_FULL_IVD,
                         static_cast<float>(a),
                         static_cast<float>(b),
                         static_cast<float>(pa / 1.5),
                         static_cast<float>(pb / 1.5),
                         iters};
    float c2, s2;
    assert_true(dfc_vector2(&c, s.g, &v, 1.5f, &c2, &s2, nullptr));
    const double ang = static_cast<double>(fd_cordic_atan2f(s2, c2));
    w_ang = std::max(w_ang, std::abs(wrap(ang - t2)));
  }
  std::printf("ref_dfc: %d cases: signals %.2e a, vector %.2e a, K %.2e, angle %.2e rad\n", n_cases,
              w_sig, w_vec, w_k, w_ang);
  assert_true(w_sig < 5e-5);
  assert_true(w_vec < 1e-4);
  assert_true(w_k < 1e-4);
  assert_true(w_ang < 1e-4);
}

} // namespace

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_against_eigen)};
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
