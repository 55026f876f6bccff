/*
 * ref_kf_mech.cpp - Eigen (double) reference of the Kalman filter on the
 * rotor's mechanics (estimation/kf_mech.h, Fabbri 2022 (4.15)-(4.21),
 * (4.46)-(4.49)), written independently with Eigen's 3x3 matrices:
 * F, G of (4.48) with the pole pairs, P- = F P F^T + Q, K = P H^T (H P H^T
 * + R)^-1, P+ = (I - K H) P (I - K H)^T + K R K^T (Joseph), the innovation
 * and the angle wrapped. A simulated rotor (random inertia, friction,
 * torque, load steps, measurement noise, 200000 periods per run) drives
 * both; the float filter stays within the stated bounds of the double one.
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

#include "estimation/kf_mech.h"
}

namespace {

using M3 = Eigen::Matrix3d;
using V3 = Eigen::Vector3d;
const double PI = 3.14159265358979323846;

double wrap(double a) {
  return std::remainder(a, 2.0 * PI);
}

void test_against_eigen(void **state) {
  (void)state;
  std::mt19937 rng(2022);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  double w_w = 0, w_th = 0, w_tl = 0, w_p = 0;
  for (int run = 0; run < 5; ++run) {
    kf_mech_cfg_t c;
    c.ts = 62.5e-6f;
    c.pole_pairs = static_cast<float>(4 + (run % 3) * 4);
    c.inertia = static_cast<float>(1e-4 * (1.0 + 9.0 * u01(rng)));
    c.friction = static_cast<float>(1e-5 * u01(rng));
    c.q[0] = 1.0f; /* (5.1) */
    c.q[1] = 0.0f;
    c.q[2] = static_cast<float>(1e-6 * (1.0 + 99.0 * u01(rng)));
    kf_mech_t k;
    assert_true(kf_mech_init(&k, &c));
    const float p0[3] = {100.0f, 0.1f, 1.0f};
    kf_mech_reset(&k, 0.3f, 0.0f, p0);
    const double T = c.ts, p = c.pole_pairs, J = c.inertia, B = c.friction;
    M3 F;
    F << 1.0 - T * B / J, 0.0, -T * p / J, T, 1.0, 0.0, 0.0, 0.0, 1.0;
    const V3 G(T * p / J, 0.0, 0.0);
    const Eigen::RowVector3d H(0.0, 1.0, 0.0);
    M3 Q = M3::Zero();
    Q.diagonal() << c.q[0], c.q[1], c.q[2];
    V3 x(0.0, 0.3, 0.0);
    M3 P = M3::Zero();
    P.diagonal() << p0[0], p0[1], p0[2];
    /* the true rotor */
    double w = 0.0, th = 0.3, tl = 0.0;
    const double r = 1e-4 * (1.0 + 9.0 * u01(rng));
    for (int n = 0; n < 200000; ++n) {
      const double te = 0.05 * std::sin(2.0 * PI * 3.0 * n * T) + (n > 100000 ? 0.02 : 0.01);
      if (n % 50000 == 0) {
        tl = 0.02 * (u01(rng) - 0.5);
      }
      /* measurement at the present angle, then the update, then the step */
      const double y = wrap(th + std::sqrt(r) * n01(rng));
      assert_true(kf_mech_update(&k, static_cast<float>(y), static_cast<float>(r)));
      {
        const double s = (H * P * H.transpose())(0, 0) + r;
        const V3 K = P * H.transpose() / s;
        const double innov = wrap(y - x(1));
        x += K * innov;
        x(1) = wrap(x(1));
        const M3 A = M3::Identity() - K * H;
        P = A * P * A.transpose() + K * r * K.transpose();
      }
      kf_mech_predict(&k, static_cast<float>(te));
      {
        x = F * x + G * te;
        x(1) = wrap(x(1));
        P = F * P * F.transpose() + Q;
      }
      /* the rotor: J dw_m/dt = T_e - T_l - B w_m */
      w += T * (p / J * (te - tl) - B / J * w);
      th = wrap(th + T * w);
      if (n > 1000) {
        w_w = std::max(w_w, std::abs(k.x[0] - x(0)) / (1.0 + std::abs(x(0))));
        w_th = std::max(w_th, std::abs(wrap(k.x[1] - x(1))));
        w_tl = std::max(w_tl, std::abs(k.x[2] - x(2)));
        const double pf[6] = {k.p[0], k.p[1], k.p[2], k.p[3], k.p[4], k.p[5]};
        const double pd[6] = {P(0, 0), P(0, 1), P(0, 2), P(1, 1), P(1, 2), P(2, 2)};
        for (int i = 0; i < 6; ++i) {
          w_p = std::max(w_p, std::abs(pf[i] - pd[i]) / (std::abs(pd[i]) + 1e-9));
        }
      }
    }
    /* the float covariance stays positive definite */
    M3 Pf;
    Pf << k.p[0], k.p[1], k.p[2], k.p[1], k.p[3], k.p[4], k.p[2], k.p[4], k.p[5];
    assert_true(Pf.llt().info() == Eigen::Success);
  }
  std::printf("ref_kf_mech: 5 runs x 200000 periods: speed %.2e (relative), angle %.2e rad, "
              "load %.2e N m, P %.2e (relative)\n",
              w_w, w_th, w_tl, w_p);
  assert_true(w_w < 1e-3);
  assert_true(w_th < 1e-4);
  assert_true(w_tl < 5e-4); /* 1 % of the 0.05 N m torque scale */
  assert_true(w_p < 1e-2);
}

/* The EKF on the DFC signals (4.35)-(4.41) against its Eigen form: H the
 * 2x3 Jacobian (4.36), K = P H^T (H P H^T + R)^-1, Joseph update; the
 * rotor at constant acceleration, signals with noise, the 4theta term
 * through the sequentiality map km (dfc_vec_t.k: q = km (cos 4theta,
 * -sin 4theta)). Also: the EKF tracks the true angle within 10 mrad rms. */
void ekf_against_eigen(const double km[4], const char *name) {
  std::mt19937 rng(4041);
  std::normal_distribution<double> n01(0.0, 1.0);
  kf_mech_cfg_t c = {62.5e-6f, 8.0f, 2e-4f, 1e-5f, {1.0f, 0.0f, 1e-6f}};
  kf_mech_t k;
  assert_true(kf_mech_init(&k, &c));
  const float p0[3] = {100.0f, 0.01f, 1.0f};
  kf_mech_reset(&k, 0.2f, 0.0f, p0);
  const double T = c.ts, p = c.pole_pairs, J = c.inertia, B = c.friction;
  Eigen::Matrix3d F;
  F << 1.0 - T * B / J, 0.0, -T * p / J, T, 1.0, 0.0, 0.0, 0.0, 1.0;
  const Eigen::Vector3d G(T * p / J, 0.0, 0.0);
  Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();
  Q.diagonal() << c.q[0], c.q[1], c.q[2];
  Eigen::Vector3d x(0.0, 0.2, 0.0);
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  P.diagonal() << p0[0], p0[1], p0[2];
  const double a = 0.05, b = -0.0047, sig = 5e-4, r = sig * sig;
  const float kmf[4] = {static_cast<float>(km[0]), static_cast<float>(km[1]),
                        static_cast<float>(km[2]), static_cast<float>(km[3])};
  const auto q4 = [km](double t4, double *qr, double *qi) {
    *qr = km[0] * std::cos(t4) - km[1] * std::sin(t4);
    *qi = km[2] * std::cos(t4) - km[3] * std::sin(t4);
  };
  double w = 0.0, th = 0.2, w_x = 0.0, w_th = 0.0, e2 = 0.0;
  int ne = 0;
  for (int n = 0; n < 64000; ++n) {
    const double te = 0.004; /* accelerates to ~ 900 rpm in 4 s */
    double qr, qi;
    q4(4 * th, &qr, &qi);
    const double ga = -a * std::cos(2 * th) + b * qr + sig * n01(rng);
    const double gb = a * std::sin(2 * th) - b * qi + sig * n01(rng);
    assert_true(kf_mech_update_ekf(&k, static_cast<float>(ga), static_cast<float>(gb),
                                   static_cast<float>(a), static_cast<float>(b), kmf,
                                   static_cast<float>(r)));
    {
      const double t2 = 2 * x(1), t4 = 4 * x(1);
      Eigen::Matrix<double, 2, 3> H = Eigen::Matrix<double, 2, 3>::Zero();
      double hr, hi; /* q at theta and its derivative (d/dtheta: 4 x (-sin, -cos) through km) */
      q4(t4, &hr, &hi);
      const double dqr = -4 * (km[0] * std::sin(t4) + km[1] * std::cos(t4));
      const double dqi = -4 * (km[2] * std::sin(t4) + km[3] * std::cos(t4));
      H(0, 1) = 2 * a * std::sin(t2) + b * dqr;
      H(1, 1) = 2 * a * std::cos(t2) - b * dqi;
      const Eigen::Matrix2d R = r * Eigen::Matrix2d::Identity();
      const Eigen::Matrix<double, 3, 2> K =
          P * H.transpose() * (H * P * H.transpose() + R).inverse();
      const Eigen::Vector2d e(ga - (-a * std::cos(t2) + b * hr), gb - (a * std::sin(t2) - b * hi));
      x += K * e;
      x(1) = wrap(x(1));
      const Eigen::Matrix3d A = Eigen::Matrix3d::Identity() - K * H;
      P = A * P * A.transpose() + K * R * K.transpose();
    }
    kf_mech_predict(&k, static_cast<float>(te));
    x = F * x + G * te;
    x(1) = wrap(x(1));
    P = F * P * F.transpose() + Q;
    w += T * (p / J * te - B / J * w);
    th = wrap(th + T * w);
    if (n > 2000) {
      w_x = std::max(w_x, std::abs(k.x[0] - x(0)) / (1.0 + std::abs(x(0))));
      w_th = std::max(w_th, std::abs(wrap(k.x[1] - x(1))));
      const double d = wrap(k.x[1] - th);
      e2 += d * d;
      ++ne;
    }
  }
  const double rms = std::sqrt(e2 / ne);
  std::printf("ref_kf_mech EKF (%s): 64000 periods: speed %.2e (relative), angle %.2e rad "
              "against Eigen; angle error %.2e rad rms against the rotor\n",
              name, w_x, w_th, rms);
  assert_true(w_x < 1e-3);
  assert_true(w_th < 1e-4);
  assert_true(rms < 0.01);
}

void test_ekf_against_eigen(void **state) {
  (void)state;
  const double eye[4] = {1.0, 0.0, 0.0, 1.0}; /* no sequentiality: (4.35) */
  ekf_against_eigen(eye, "K = I");
}

/* The 4theta term turned and scaled as the sequentiality compensation maps
 * it at speed (here 0.4 rad, x 0.95, fixed): the filter's h and H follow
 * km (an EKF on (4.35) with K = I would be 20 mrad off the reference). */
void test_ekf_sequentiality_map_against_eigen(void **state) {
  (void)state;
  const double r = 0.95, c = r * std::cos(0.4), s = r * std::sin(0.4);
  const double km[4] = {c, -s, s, c};
  ekf_against_eigen(km, "K turned 0.4 rad");
}

} // namespace

int main(void) {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_against_eigen),
                                     cmocka_unit_test(test_ekf_against_eigen),
                                     cmocka_unit_test(test_ekf_sequentiality_map_against_eigen)};
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
