/*
 * plant_fluxmap.c - the plant's flux map and its inverse (plant_fluxmap.h).
 */
#include "plant_fluxmap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "plant_bicubic.h"

struct plant_fluxmap {
  plant_bicubic_t fwd; /* lambda(i) */
  plant_bicubic_t inv; /* i(lambda) */
  double flux0[2];
  double l_min;
  int nonunique, extrapolated;
  char first_bad[160];
};

/* Smallest eigenvalue of the symmetric part of a 2x2 matrix. */
static double eig_min(const double l[2][2]) {
  const double a = l[0][0], d = l[1][1], c = 0.5 * (l[0][1] + l[1][0]);
  const double m = 0.5 * (a + d), r = sqrt(0.25 * (a - d) * (a - d) + c * c);
  return m - r;
}

/* Grid checks with the cell named: finite values, positive incremental
 * self-inductances and a positive-definite incremental matrix from the
 * cell's mean differences. */
static int check_grid(const plant_fluxmap_grid_t *g, char *err, size_t n) {
  if (g->nd < 2 || g->nq < 2 || !(g->did > 0.0) || !(g->diq > 0.0) || !isfinite(g->id0) ||
      !isfinite(g->iq0) || !isfinite(g->did) || !isfinite(g->diq)) {
    snprintf(err, n, "grid: at least 2 x 2 points with finite axes and positive steps");
    return -1;
  }
  for (int o = 0; o < g->nd * g->nq; ++o) {
    if (!isfinite(g->psi_d[o]) || !isfinite(g->psi_q[o])) {
      snprintf(err, n, "flux not finite at grid point (%d, %d)", o % g->nd, o / g->nd);
      return -1;
    }
  }
  for (int k = 0; k + 1 < g->nq; ++k) {
    for (int j = 0; j + 1 < g->nd; ++j) {
      const int o = k * g->nd + j, s = g->nd;
      const double *d = g->psi_d, *q = g->psi_q;
      const double l[2][2] = {{0.5 * (d[o + 1] - d[o] + d[o + s + 1] - d[o + s]) / g->did,
                               0.5 * (d[o + s] - d[o] + d[o + s + 1] - d[o + 1]) / g->diq},
                              {0.5 * (q[o + 1] - q[o] + q[o + s + 1] - q[o + s]) / g->did,
                               0.5 * (q[o + s] - q[o] + q[o + s + 1] - q[o + 1]) / g->diq}};
      if (!(l[0][0] > 0.0 && l[1][1] > 0.0 && eig_min(l) > 0.0)) {
        snprintf(err, n,
                 "incremental inductance matrix not positive definite in grid cell (%d, %d) "
                 "(i_d = %g A, i_q = %g A)",
                 j, k, g->id0 + j * g->did, g->iq0 + k * g->diq);
        return -1;
      }
    }
  }
  return 0;
}

/* Newton on the forward patches: i with lambda(i) = target, from i. 1 when
 * converged. */
static int solve(const plant_bicubic_t *fwd, const double target[2], double i[2]) {
  for (int it = 0; it < 60; ++it) {
    double f[2], J[2][2];
    plant_bicubic_eval(fwd, i[0], i[1], f, J);
    const double r0 = target[0] - f[0], r1 = target[1] - f[1];
    const double det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    if (!(fabs(det) > 0.0)) {
      return 0;
    }
    const double s0 = (J[1][1] * r0 - J[0][1] * r1) / det;
    const double s1 = (J[0][0] * r1 - J[1][0] * r0) / det;
    i[0] += s0;
    i[1] += s1;
    if (fabs(r0) + fabs(r1) < 1e-13 * (1.0 + fabs(target[0]) + fabs(target[1]))) {
      return 1;
    }
  }
  return 0;
}

static int build_inverse(plant_fluxmap_t *m, const plant_fluxmap_grid_t *g, char *err, size_t n) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (int o = 0; o < g->nd * g->nq; ++o) {
    const double v[2] = {g->psi_d[o], g->psi_q[o]};
    for (int c = 0; c < 2; ++c) {
      lo[c] = v[c] < lo[c] ? v[c] : lo[c];
      hi[c] = v[c] > hi[c] ? v[c] : hi[c];
    }
  }
  int ni[2] = {PLANT_FLUXMAP_REFINE * (g->nd - 1) + 1, PLANT_FLUXMAP_REFINE * (g->nq - 1) + 1};
  double step[2];
  for (int c = 0; c < 2; ++c) {
    ni[c] = ni[c] > PLANT_FLUXMAP_INV_MAX ? PLANT_FLUXMAP_INV_MAX : ni[c];
    const double pad = 0.02 * (hi[c] - lo[c]) + 1e-9;
    lo[c] -= pad;
    hi[c] += pad;
    step[c] = (hi[c] - lo[c]) / (ni[c] - 1);
  }
  const size_t nn = (size_t)ni[0] * (size_t)ni[1];
  double *cd = malloc(2 * nn * sizeof *cd);
  if (cd == NULL) {
    snprintf(err, n, "out of memory");
    return -1;
  }
  const double ie[2] = {g->id0 + (g->nd - 1) * g->did, g->iq0 + (g->nq - 1) * g->diq};
  double row0[2] = {0.0, 0.0};
  for (int k = 0; k < ni[1]; ++k) {
    double i[2] = {row0[0], row0[1]};
    for (int j = 0; j < ni[0]; ++j) {
      const double target[2] = {lo[0] + j * step[0], lo[1] + k * step[1]};
      int ok = solve(&m->fwd, target, i);
      if (!ok) { /* a fresh start from zero current */
        i[0] = i[1] = 0.0;
        ok = solve(&m->fwd, target, i);
      }
      double f[2], J[2][2];
      plant_bicubic_eval(&m->fwd, i[0], i[1], f, J);
      if (!ok || !(J[0][0] > 0.0 && J[1][1] > 0.0 && eig_min(J) > 0.0)) {
        if (m->nonunique++ == 0) {
          snprintf(m->first_bad, sizeof m->first_bad, "flux (%g, %g) Vs: %s near i = (%g, %g) A",
                   target[0], target[1],
                   ok ? "incremental inductance not positive definite" : "Newton did not converge",
                   i[0], i[1]);
        }
      }
      if (i[0] < g->id0 || i[0] > ie[0] || i[1] < g->iq0 || i[1] > ie[1]) {
        m->extrapolated++;
      }
      cd[(size_t)k * (size_t)ni[0] + (size_t)j] = i[0];
      cd[nn + (size_t)k * (size_t)ni[0] + (size_t)j] = i[1];
      if (j == 0) {
        row0[0] = i[0];
        row0[1] = i[1];
      }
    }
  }
  const int rc =
      plant_bicubic_build(&m->inv, ni[0], ni[1], lo[0], step[0], lo[1], step[1], cd, cd + nn);
  free(cd);
  if (rc != 0) {
    snprintf(err, n, "out of memory");
  }
  return rc;
}

int plant_fluxmap_create(const plant_fluxmap_grid_t *g, plant_fluxmap_t **out, char *err,
                         size_t errlen) {
  *out = NULL;
  if (check_grid(g, err, errlen) != 0) {
    return -1;
  }
  plant_fluxmap_t *m = calloc(1, sizeof *m);
  if (m == NULL || plant_bicubic_build(&m->fwd, g->nd, g->nq, g->id0, g->did, g->iq0, g->diq,
                                       g->psi_d, g->psi_q) != 0) {
    snprintf(err, errlen, "out of memory");
    free(m);
    return -1;
  }
  m->l_min = INFINITY;
  for (int k = 0; k < g->nq; ++k) {
    for (int j = 0; j < g->nd; ++j) {
      double f[2], J[2][2];
      plant_bicubic_eval(&m->fwd, g->id0 + j * g->did, g->iq0 + k * g->diq, f, J);
      const double e = eig_min(J);
      m->l_min = e < m->l_min ? e : m->l_min;
    }
  }
  plant_bicubic_eval(&m->fwd, 0.0, 0.0, m->flux0, NULL);
  if (!(m->l_min > 0.0)) {
    snprintf(err, errlen, "the interpolated map is not positive definite at a grid point");
    plant_fluxmap_free(m);
    return -1;
  }
  if (build_inverse(m, g, err, errlen) != 0) {
    plant_fluxmap_free(m);
    return -1;
  }
  *out = m;
  return 0;
}

void plant_fluxmap_free(plant_fluxmap_t *m) {
  if (m != NULL) {
    plant_bicubic_free(&m->fwd);
    plant_bicubic_free(&m->inv);
    free(m);
  }
}

void plant_fluxmap_flux(const plant_fluxmap_t *m, double i_d, double i_q, double *psi_d,
                        double *psi_q) {
  double f[2];
  plant_bicubic_eval(&m->fwd, i_d, i_q, f, NULL);
  *psi_d = f[0];
  *psi_q = f[1];
}

void plant_fluxmap_current(const plant_fluxmap_t *m, double psi_d, double psi_q, double *i_d,
                           double *i_q) {
  double f[2];
  plant_bicubic_eval(&m->inv, psi_d, psi_q, f, NULL);
  *i_d = f[0];
  *i_q = f[1];
}

void plant_fluxmap_jacobian(const plant_fluxmap_t *m, double psi_d, double psi_q,
                            double jac[2][2]) {
  double f[2];
  plant_bicubic_eval(&m->inv, psi_d, psi_q, f, jac);
}

void plant_fluxmap_flux0(const plant_fluxmap_t *m, double *psi_d, double *psi_q) {
  *psi_d = m->flux0[0];
  *psi_q = m->flux0[1];
}

double plant_fluxmap_l_min(const plant_fluxmap_t *m) {
  return m->l_min;
}

int plant_fluxmap_nonunique(const plant_fluxmap_t *m, char *msg, size_t n) {
  if (msg != NULL && n > 0) {
    snprintf(msg, n, "%s", m->nonunique > 0 ? m->first_bad : "");
  }
  return m->nonunique;
}

int plant_fluxmap_extrapolated(const plant_fluxmap_t *m) {
  return m->extrapolated;
}
