/*
 * plant_bicubic.c - bicubic Hermite patches (plant_bicubic.h).
 */
#include "plant_bicubic.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>

/* Slopes (per unit step) of the natural cubic spline through n values
 * f[0], f[s], ..., f[(n-1) s], into m[0], m[s], ...: the tridiagonal system
 * m[i-1] + 4 m[i] + m[i+1] = 3 (f[i+1] - f[i-1]), 2 m[0] + m[1] = 3 (f[1] - f[0])
 * and its mirror at the end (Thomas algorithm; w: n scratch values). */
static void spline_slopes(const double *f, double *m, ptrdiff_t n, ptrdiff_t s, double *w) {
  if (n == 2) {
    m[0] = m[s] = f[s] - f[0];
    return;
  }
  /* forward sweep: w holds the modified super-diagonal */
  double b = 2.0;
  w[0] = 1.0 / b;
  m[0] = 3.0 * (f[s] - f[0]) / b;
  for (ptrdiff_t i = 1; i < n; ++i) {
    /* mut: plant_spline_end_condition */
    const double diag = i == n - 1 ? 2.0 : 4.0;
    const double rhs =
        i == n - 1 ? 3.0 * (f[i * s] - f[(i - 1) * s]) : 3.0 * (f[(i + 1) * s] - f[(i - 1) * s]);
    b = diag - w[i - 1];
    w[i] = 1.0 / b;
    m[i * s] = (rhs - m[(i - 1) * s]) / b;
  }
  for (ptrdiff_t i = n - 2; i >= 0; --i) {
    m[i * s] -= w[i] * m[(i + 1) * s];
  }
}

/* Values, x slopes, y slopes and cross slopes of the tensor-product
 * natural cubic spline at every node (per unit step). */
typedef struct {
  double *fx, *fy, *fxy;
} slopes_t;

static int node_slopes(const double *f, int nx, int ny, slopes_t *o) {
  const size_t n = (size_t)nx * (size_t)ny;
  o->fx = malloc(3 * n * sizeof *o->fx);
  double *w = malloc((size_t)(nx > ny ? nx : ny) * sizeof *w);
  if (o->fx == NULL || w == NULL) {
    free(o->fx);
    free(w);
    return -1;
  }
  o->fy = o->fx + n;
  o->fxy = o->fy + n;
  for (ptrdiff_t k = 0; k < ny; ++k) {
    spline_slopes(f + k * nx, o->fx + k * nx, nx, 1, w);
  }
  for (int j = 0; j < nx; ++j) {
    spline_slopes(f + j, o->fy + j, ny, nx, w);
    spline_slopes(o->fx + j, o->fxy + j, ny, nx, w);
  }
  free(w);
  return 0;
}

/* Coefficients A = M F M^T of the patch (F: values, u-slopes, v-slopes and
 * cross slopes at the corners), M the cubic Hermite matrix: with the
 * spline's node slopes the patches are the bicubic spline itself (C2). */
static void patch(const double *f, const slopes_t *sl, int j, int k, int nx, double a[16]) {
  static const double M[4][4] = {{1, 0, 0, 0}, {0, 0, 1, 0}, {-3, 3, -2, -1}, {2, -2, 1, 1}};
  double F[4][4];
  for (int dj = 0; dj < 2; ++dj) {
    for (int dk = 0; dk < 2; ++dk) {
      const int o = (k + dk) * nx + j + dj;
      F[dj][dk] = f[o];
      F[2 + dj][dk] = sl->fx[o];
      F[dj][2 + dk] = sl->fy[o];
      F[2 + dj][2 + dk] = sl->fxy[o];
    }
  }
  double T[4][4];
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      double t = 0.0;
      for (int q = 0; q < 4; ++q) {
        t += M[r][q] * F[q][c];
      }
      T[r][c] = t;
    }
  }
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      double t = 0.0;
      for (int q = 0; q < 4; ++q) {
        t += T[r][q] * M[c][q];
      }
      a[4 * r + c] = t; /* coefficient of u^r v^c */
    }
  }
}

int plant_bicubic_build(plant_bicubic_t *b, int nx, int ny, double x0, double dx, double y0,
                        double dy, const double *f1, const double *f2) {
  b->nx = nx;
  b->ny = ny;
  b->x0 = x0;
  b->dx = dx;
  b->y0 = y0;
  b->dy = dy;
  b->inv_dx = 1.0 / dx;
  b->inv_dy = 1.0 / dy;
  b->c = malloc((size_t)(nx - 1) * (size_t)(ny - 1) * 32u * sizeof *b->c);
  if (b->c == NULL) {
    return -1;
  }
  slopes_t s1, s2;
  if (node_slopes(f1, nx, ny, &s1) != 0) {
    plant_bicubic_free(b);
    return -1;
  }
  if (node_slopes(f2, nx, ny, &s2) != 0) {
    free(s1.fx);
    plant_bicubic_free(b);
    return -1;
  }
  for (int k = 0; k + 1 < ny; ++k) {
    for (int j = 0; j + 1 < nx; ++j) {
      double *a = b->c + ((size_t)k * (size_t)(nx - 1) + (size_t)j) * 32u;
      patch(f1, &s1, j, k, nx, a);
      patch(f2, &s2, j, k, nx, a + 16);
    }
  }
  free(s1.fx);
  free(s2.fx);
  return 0;
}

void plant_bicubic_free(plant_bicubic_t *b) {
  free(b->c);
  b->c = NULL;
}

static double clampd(double x, double lo, double hi) {
  return x < lo ? lo : (x > hi ? hi : x);
}

/* Inside the box: f = U^T A V with U = (1, u, u^2, u^3), V alike (16
 * independent products per component: more parallel than Horner); the
 * derivatives from dU, dV only when asked for (the integration asks for
 * currents far more often than for the Jacobian). */
static void eval_in(const plant_bicubic_t *b, double x, double y, double f[2], double jac[2][2]) {
  const double X = (x - b->x0) * b->inv_dx, Y = (y - b->y0) * b->inv_dy;
  int j = (int)X, k = (int)Y;
  j = j > b->nx - 2 ? b->nx - 2 : j;
  k = k > b->ny - 2 ? b->ny - 2 : k;
  const double u = X - j, v = Y - k;
  const double U[4] = {1.0, u, u * u, u * u * u}, V[4] = {1.0, v, v * v, v * v * v};
  const double *a = b->c + ((size_t)k * (size_t)(b->nx - 1) + (size_t)j) * 32u;
  for (int c = 0; c < 2; ++c, a += 16) {
    double t[4];
    for (int r = 0; r < 4; ++r) {
      const double *ar = a + (ptrdiff_t)4 * r;
      t[r] = ar[0] + ar[1] * V[1] + ar[2] * V[2] + ar[3] * V[3];
    }
    f[c] = t[0] + U[1] * t[1] + U[2] * t[2] + U[3] * t[3];
    if (jac != NULL) {
      const double dV[4] = {0.0, 1.0, 2.0 * v, 3.0 * v * v};
      double tv = 0.0;
      for (int r = 0; r < 4; ++r) {
        const double *ar = a + (ptrdiff_t)4 * r;
        tv += U[r] * (ar[1] * dV[1] + ar[2] * dV[2] + ar[3] * dV[3]);
      }
      jac[c][0] = (t[1] + 2.0 * u * t[2] + 3.0 * u * u * t[3]) * b->inv_dx;
      jac[c][1] = tv * b->inv_dy;
    }
  }
}

void plant_bicubic_eval(const plant_bicubic_t *b, double x, double y, double f[2],
                        double jac[2][2]) {
  const double xe = b->x0 + (b->nx - 1) * b->dx, ye = b->y0 + (b->ny - 1) * b->dy;
  if (isnan(x) || isnan(y)) {
    f[0] = f[1] = NAN;
    if (jac != NULL) {
      jac[0][0] = jac[0][1] = jac[1][0] = jac[1][1] = NAN;
    }
    return;
  }
  if (x >= b->x0 && x <= xe && y >= b->y0 && y <= ye) {
    eval_in(b, x, y, f, jac);
    return;
  }
  const double xc = clampd(x, b->x0, xe), yc = clampd(y, b->y0, ye);
  double J[2][2];
  eval_in(b, xc, yc, f, J);
  for (int c = 0; c < 2; ++c) {
    f[c] += J[c][0] * (x - xc) + J[c][1] * (y - yc);
    if (jac != NULL) {
      jac[c][0] = J[c][0];
      jac[c][1] = J[c][1];
    }
  }
}
