/*
 * plant_bicubic.h - a smooth two-valued function of two variables on a
 * regular grid for the plant's flux maps: the tensor-product natural cubic
 * spline (C2 across cells; node slopes and cross slopes from the spline's
 * tridiagonal systems), stored as the 16 polynomial coefficients
 * of each cell and component so that an evaluation is one cell lookup and
 * a Horner scheme. Outside the grid the function continues linearly from
 * the nearest point of the grid's box with the Jacobian there (continuous,
 * no cubic run-away).
 */
#ifndef FD_PLANT_BICUBIC_H
#define FD_PLANT_BICUBIC_H

typedef struct {
  int nx, ny;            /* nodes, >= 2 each */
  double x0, dx, y0, dy; /* node (j, k) at (x0 + j dx, y0 + k dy) */
  double inv_dx, inv_dy;
  double *c; /* [(ny-1)(nx-1)][2][16]: a_mn of f_c(u, v) = sum a_mn u^m v^n */
} plant_bicubic_t;

/* Builds the patches from node values f1, f2 (index k nx + j). 0, or -1
 * when out of memory. */
int plant_bicubic_build(plant_bicubic_t *b, int nx, int ny, double x0, double dx, double y0,
                        double dy, const double *f1, const double *f2);
void plant_bicubic_free(plant_bicubic_t *b);
/* f1, f2 at (x, y); with jac != NULL also jac[r][c] = d f_r / d (x, y)_c. */
void plant_bicubic_eval(const plant_bicubic_t *b, double x, double y, double f[2],
                        double jac[2][2]);

#endif
