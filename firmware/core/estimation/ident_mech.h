/*
 * ident_mech.h - least squares of the mechanical equation (issue 25 g):
 * J dw/dt = T - T_c sgn(w) - B w, integrated over windows [t0, t1]:
 *   J (w(t1) - w(t0)) + T_c int sgn(w) dt + B int w dt = int T dt,
 * one row a = (w(t1) - w(t0), int sgn(w) dt, int w dt), y = int T dt per
 * window; the normal equations A^T A x = A^T y accumulated (Ljung, System
 * Identification, 2nd ed., eq. (7.34)), solved for x = (J, T_c, B) once.
 * The caller scales the columns to O(1) (float: the normal matrix squares
 * the columns' condition).
 */
#ifndef FD_ESTIMATION_IDENT_MECH_H
#define FD_ESTIMATION_IDENT_MECH_H

/* ls[10]: the upper triangle of A^T A (00 01 02 11 12 22), A^T y (3), y^T y */
#define IDENT_MECH_LS 10

void ident_mech_reset(float ls[IDENT_MECH_LS]);
/* One row a[3], y. */
void ident_mech_add(float ls[IDENT_MECH_LS], const float a[3], float y);
/* x = (A^T A)^-1 A^T y; *rms: the fit's rms residual per row over the rms
 * of y (0 .. 1). Returns 0, or -1 when A^T A is singular (too few rows, or
 * a column without excitation). */
int ident_mech_solve(const float ls[IDENT_MECH_LS], unsigned rows, float x[3], float *rms);

#endif
