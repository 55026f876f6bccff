/*
 * ref_flux_map.cpp - Eigen (double) reference of the core's flux map
 * (model/flux_map.c): the bilinear interpolant written as the matrix
 * product [1-v v] F [1-u u]^T on the cell's corner matrix F, the
 * incremental inductance matrix of Varatharajan (25) centred over one grid
 * step, and the inverse i(lambda) by Newton with Eigen's 2x2 solve,
 * iterated to convergence. Compared with the float core over random points
 * (inside and outside the grid) within float rounding.
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

#include "flux_map_fixture.h"
#include "model/flux_map.h"
}

namespace {

uint32_t g_blob[FX_WORDS];

struct RefMap {
  int nd, nq;
  double id0, did, iq0, diq;
  Eigen::MatrixXd pd, pq; /* (k, j): row = i_q index */

  explicit RefMap(const uint32_t *w) {
    nd = static_cast<int>(w[3]);
    nq = static_cast<int>(w[4]);
    auto f = [w](int i) {
      float x;
      std::memcpy(&x, &w[i], sizeof x);
      return static_cast<double>(x);
    };
    id0 = f(8);
    did = f(9);
    iq0 = f(10);
    diq = f(11);
    pd.resize(nq, nd);
    pq.resize(nq, nd);
    for (int k = 0; k < nq; ++k) {
      for (int j = 0; j < nd; ++j) {
        pd(k, j) = f(12 + k * nd + j);
        pq(k, j) = f(12 + nd * nq + k * nd + j);
      }
    }
  }

  /* cell (clamped) and the position inside it (unclamped) */
  void cell(const Eigen::Vector2d &i, int &j, int &k, double &u, double &v) const {
    const double x = (i(0) - id0) / did, y = (i(1) - iq0) / diq;
    j = static_cast<int>(std::floor(std::min(std::max(x, 0.0), nd - 2.0)));
    k = static_cast<int>(std::floor(std::min(std::max(y, 0.0), nq - 2.0)));
    u = x - j;
    v = y - k;
  }

  Eigen::Vector2d flux(const Eigen::Vector2d &i) const {
    int j, k;
    double u, v;
    cell(i, j, k, u, v);
    const Eigen::RowVector2d wv(1.0 - v, v);
    const Eigen::Vector2d wu(1.0 - u, u);
    return Eigen::Vector2d(wv * pd.block<2, 2>(k, j) * wu, wv * pq.block<2, 2>(k, j) * wu);
  }

  /* the interpolant's own Jacobian (Newton) */
  Eigen::Matrix2d jac(const Eigen::Vector2d &i) const {
    int j, k;
    double u, v;
    cell(i, j, k, u, v);
    const Eigen::RowVector2d wv(1.0 - v, v), dv(-1.0, 1.0);
    const Eigen::Vector2d wu(1.0 - u, u), du(-1.0, 1.0);
    Eigen::Matrix2d l;
    l << wv * pd.block<2, 2>(k, j) * du / did, dv * pd.block<2, 2>(k, j) * wu / diq,
        wv * pq.block<2, 2>(k, j) * du / did, dv * pq.block<2, 2>(k, j) * wu / diq;
    return l;
  }

  /* (25) centred: columns d/di_d, d/di_q */
  Eigen::Matrix2d inductance(const Eigen::Vector2d &i) const {
    const Eigen::Vector2d hd(0.5 * did, 0.0), hq(0.0, 0.5 * diq);
    Eigen::Matrix2d l;
    l.col(0) = (flux(i + hd) - flux(i - hd)) / did;
    l.col(1) = (flux(i + hq) - flux(i - hq)) / diq;
    return l;
  }

  Eigen::Vector2d current(const Eigen::Vector2d &lambda) const {
    Eigen::Vector2d i =
        jac(Eigen::Vector2d::Zero()).lu().solve(lambda - flux(Eigen::Vector2d::Zero()));
    for (int n = 0; n < 15; ++n) {
      i += jac(i).lu().solve(lambda - flux(i));
    }
    return i;
  }
};

void check(double got, double want, double tol, const char *what, double x, double y) {
  if (!(std::fabs(got - want) <= tol)) {
    fail_msg("%s at (%.4f, %.4f): got %.9g want %.9g (|err| %.3g > %.3g)", what, x, y, got, want,
             std::fabs(got - want), tol);
  }
}

void test_against_eigen(void **) {
  for (const fx_model_t *model : {&FX_SYR, &FX_PM}) {
    const uint32_t n = fx_build(model, g_blob);
    flux_map_t fm;
    assert_int_equal(flux_map_parse(&fm, g_blob, n, nullptr), 0);
    const RefMap ref(g_blob);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> cur(-6.5, 6.5); /* a little outside the grid too */
    double worst_f = 0.0, worst_l = 0.0, worst_i = 0.0;
    for (int s = 0; s < 3000; ++s) {
      const Eigen::Vector2d i(cur(rng), cur(rng));
      const dq_t fi = {static_cast<float>(i(0)), static_cast<float>(i(1))};
      const Eigen::Vector2d ir(static_cast<double>(fi.d), static_cast<double>(fi.q));
      const Eigen::Vector2d f = ref.flux(ir);
      const dq_t ff = flux_map_flux(&fm, fi);
      check(ff.d, f(0), 2e-6 * (1.0 + std::fabs(f(0))), "lambda_d", ir(0), ir(1));
      check(ff.q, f(1), 2e-6 * (1.0 + std::fabs(f(1))), "lambda_q", ir(0), ir(1));
      worst_f = std::max(worst_f, std::max(std::fabs(ff.d - f(0)), std::fabs(ff.q - f(1))));
      const Eigen::Matrix2d l = ref.inductance(ir);
      const flux_map_ldq_t lf = flux_map_inductance(&fm, fi);
      const double tl = 1e-4 * (std::fabs(l(0, 0)) + std::fabs(l(1, 1)));
      check(lf.dd, l(0, 0), tl, "l_dd", ir(0), ir(1));
      check(lf.dq, l(0, 1), tl, "l_dq", ir(0), ir(1));
      check(lf.qd, l(1, 0), tl, "l_qd", ir(0), ir(1));
      check(lf.qq, l(1, 1), tl, "l_qq", ir(0), ir(1));
      worst_l = std::max(
          worst_l, (l - Eigen::Matrix2d{{lf.dd, lf.dq}, {lf.qd, lf.qq}}).cwiseAbs().maxCoeff());
      if (std::fabs(i(0)) < 6.0 && std::fabs(i(1)) < 6.0) {
        const Eigen::Vector2d ic = ref.current(f);
        const dq_t icf = flux_map_current(&fm, ff);
        check(icf.d, ic(0), 1e-3, "i_d(lambda)", ir(0), ir(1));
        check(icf.q, ic(1), 1e-3, "i_q(lambda)", ir(0), ir(1));
        worst_i = std::max(worst_i, std::max(std::fabs(icf.d - ic(0)), std::fabs(icf.q - ic(1))));
      }
    }
    std::printf("flux map vs Eigen (%s): flux %.3g Vs, inductance %.3g H, inverse %.3g A\n",
                model->lm > 0.0 ? "PM" : "SyR", worst_f, worst_l, worst_i);
  }
}

} // namespace

int main() {
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_against_eigen)};
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
