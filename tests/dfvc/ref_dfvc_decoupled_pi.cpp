/*
 * ref_dfvc_decoupled_pi.cpp - Eigen (double) reference of the regulators of the
 * decoupled DFVC (control/dfvc_decoupled_pi.h, Varatharajan 2022 (26)-(28)):
 *  - the gains: the closed loop of each axis, y(k+1) = y(k) + Ts u(k) with
 *    u = kp e + I, I += ki Ts e, written as a 2x2 state matrix in double
 *    with the float core's kp, ki, has its two eigenvalues at
 *    p = exp(-Omega Ts) (the double pole of (28) in discrete form), for
 *    Omega Ts over the whole range the drive allows;
 *  - one step: the same equations in double (prediction, PI, the
 *    transformation T of (23) as a matrix, the voltage circle with the flux
 *    axis first, conditional integration, the applied virtual inputs)
 *    against the float core over long random sequences (references,
 *    predictions, gains, limits: saturated and not), the state carried in
 *    both and compared every step.
 */
#include <algorithm>
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

#include "control/dfvc_decoupled_pi.h"
}

namespace {

void test_double_pole(void **state) {
  (void)state;
  double worst = 0.0;
  for (int n = 0; n < 200; ++n) {
    const double ts = (n % 2) ? 2e-4 : 6.25e-5;
    const double omega = 10.0 + 50.0 * n; /* Omega Ts up to 2 */
    dfvc_decoupled_pi_t c;
    const dfvc_decoupled_pi_cfg_t cfg = {static_cast<float>(ts), static_cast<float>(omega), 1e4f};
    assert_int_equal(dfvc_decoupled_pi_init(&c, &cfg), 0);
    /* state (y, I): e = -y (r = 0); I' = I - ki Ts y; y' = y + Ts (-kp y + I') */
    const double kp = c.kp, ki = c.ki;
    Eigen::Matrix2d a;
    a << 1.0 - ts * kp - ki * ts * ts, ts, -ki * ts, 1.0;
    Eigen::EigenSolver<Eigen::Matrix2d> es(a);
    const double p = std::exp(-omega * ts);
    for (int k = 0; k < 2; ++k) {
      worst = std::max(worst, std::abs(es.eigenvalues()(k) - std::complex<double>(p, 0.0)));
    }
  }
  std::printf("closed-loop eigenvalues vs exp(-Omega Ts): worst %.2g\n", worst);
  /* a double root moves by sqrt of the coefficients' float rounding */
  assert_true(worst < 2e-3);
}

struct Ref {
  double kp, ki, ts, vfmax;
  double integ_f = 0.0, integ_t = 0.0, u_t_prev = 0.0;

  Eigen::Vector2d step(const dfvc_decoupled_pi_in_t &in) {
    const double itau_pred = in.i_ft.q + ts * u_t_prev;
    const double e_f = in.lambda_ref - in.lambda_next;
    const double e_t = in.itau_ref - itau_pred;
    const double int_f = integ_f + ki * ts * e_f;
    const double int_t = integ_t + ki * ts * e_t;
    const Eigen::Vector2d u(kp * e_f + int_f, kp * e_t + int_t);
    Eigen::Matrix2d t; /* (23) */
    t << 1.0, 0.0, -in.g.a / in.g.b, 1.0 / in.g.b;
    const Eigen::Vector2d ff(in.rs * in.i_ft.d, in.rs * in.i_ft.q + in.omega_r * in.lambda_next);
    const Eigen::Vector2d raw = ff + t * u;
    const double vmax = std::max(double(in.v_max), 0.0);
    const double lf = std::min(vfmax, vmax);
    const double vf = std::clamp(raw(0), -lf, lf);
    const double lt = std::sqrt(std::max(vmax * vmax - vf * vf, 0.0));
    const double vt = std::clamp(raw(1), -lt, lt);
    const bool sf = raw(0) > lf || raw(0) < -lf;
    const bool st = raw(1) > lt || raw(1) < -lt;
    if (!(sf && (raw(0) - vf) * e_f > 0.0)) {
      integ_f = int_f;
    }
    if (!(st && (raw(1) - vt) * e_t > 0.0)) {
      integ_t = int_t;
    }
    const Eigen::Vector2d ua = t.inverse() * (Eigen::Vector2d(vf, vt) - ff); /* (21) */
    u_t_prev = ua(1);
    return Eigen::Vector2d(vf, vt);
  }
};

void test_step_against_eigen(void **state) {
  (void)state;
  std::mt19937 rng(2022);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  double worst = 0.0;
  double worst_state = 0.0;
  int saturated = 0;
  for (int run = 0; run < 200; ++run) {
    const float ts = (run % 2) ? 2e-4f : 6.25e-5f;
    const float omega = static_cast<float>(2 * 3.14159265 * (50.0 + 250.0 * u01(rng)));
    dfvc_decoupled_pi_t c;
    const dfvc_decoupled_pi_cfg_t cfg = {ts, omega, (run % 3) ? 1e4f : 60.0f};
    assert_int_equal(dfvc_decoupled_pi_init(&c, &cfg), 0);
    Ref r{c.kp, c.ki, ts, cfg.v_f_max};
    const float a = static_cast<float>(10.0 * u01(rng));
    const float b = static_cast<float>(2.0 + 40.0 * u01(rng));
    for (int k = 0; k < 500; ++k) {
      dfvc_decoupled_pi_in_t in;
      in.lambda_ref = static_cast<float>(0.2 + u01(rng));
      in.itau_ref = static_cast<float>(4.0 * (2.0 * u01(rng) - 1.0));
      in.lambda_next = in.lambda_ref + static_cast<float>(0.02 * (2.0 * u01(rng) - 1.0));
      in.i_ft = {static_cast<float>(2.0 * u01(rng)),
                 in.itau_ref + static_cast<float>(0.1 * (2.0 * u01(rng) - 1.0))};
      in.omega_r = static_cast<float>(600.0 * u01(rng));
      in.rs = 6.8f;
      in.g = {a, b};
      in.v_max = static_cast<float>(50.0 + 300.0 * u01(rng));
      dfvc_decoupled_pi_out_t out;
      dfvc_decoupled_pi_step(&c, &in, &out);
      const Eigen::Vector2d v = r.step(in);
      saturated += out.sat != 0u;
      const double scale = 1.0 + std::abs(v(0)) + std::abs(v(1));
      worst = std::max(worst, (std::abs(out.v_ft.d - v(0)) + std::abs(out.v_ft.q - v(1))) / scale);
      /* the state the step left (conditional integration, the applied
       * virtual input), then carried into the reference: the comparison is
       * per step, not of two drifting integrations */
      const double ss = 1.0 + std::abs(r.integ_f) + std::abs(r.integ_t) + std::abs(r.u_t_prev);
      worst_state =
          std::max(worst_state, (std::abs(c.integ_f - r.integ_f) + std::abs(c.integ_t - r.integ_t) +
                                 std::abs(c.u_t_prev - r.u_t_prev)) /
                                    ss);
      r.integ_f = c.integ_f;
      r.integ_t = c.integ_t;
      r.u_t_prev = c.u_t_prev;
    }
  }
  std::printf("regulator step vs Eigen over 100000 steps (%d on a limit): worst %.2g of the "
              "voltage scale, state %.2g\n",
              saturated, worst, worst_state);
  assert_true(saturated > 1000); /* both regimes exercised */
  /* float rounding of the errors (lambda* - lambda, ulp 6e-8 Vs) times kp
   * (up to 1.5e4 1/s): ~1e-3 V against a scale of ~100 V (measured 8.9e-6) */
  assert_true(worst < 3e-5);
  /* u_tau applied = b (v - ff) + a u_f: the rounding of v - ff (~100 V
   * quantities) times b (up to 42 1/H), measured 5.7e-5; the conditional
   * integration with its sign reversed: 3 */
  assert_true(worst_state < 3e-4);
}

} // namespace

int main() {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_double_pole),
                                     cmocka_unit_test(test_step_against_eigen)};
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
