/*
 * plant_fluxmap.h - the plant's saturated machine: a flux map lambda(i)
 * given on a regular current grid (fluxdrive frame, docs/flux-maps.md),
 * inverted once at load time onto a regular flux grid so that the
 * integration (flux linkages are the state) gets the currents i(lambda)
 * and their Jacobian d i / d lambda from one smooth interpolant.
 *
 * Forward map: the bicubic natural spline through the grid values
 * (plant_bicubic.h, C2). Inverse: on a flux grid of PLANT_FLUXMAP_REFINE
 * times the current grid's points per axis (at most PLANT_FLUXMAP_INV_MAX),
 * covering the image of the current grid, each node solved by Newton on
 * the forward patches (continuation from the neighbouring node), then
 * the bicubic spline through those currents: i(lambda) is C2 and its
 * Jacobian is the spline's own derivative (consistent with the currents:
 * the diode projection and the energy balance rely on it). Measured error
 * of the inverse against the forward patches, and of both against a
 * closed-form machine: tests/plant/test_fluxmap.c prints them.
 * Outside the flux grid the currents continue linearly (never NaN, never
 * a crash); flux-grid nodes whose solution lies outside the current grid
 * are extrapolated and counted.
 */
#ifndef FD_PLANT_FLUXMAP_H
#define FD_PLANT_FLUXMAP_H

#include <stddef.h>

#define PLANT_FLUXMAP_REFINE  2
#define PLANT_FLUXMAP_INV_MAX 161

typedef struct {
  int nd, nq;                  /* forward grid points, >= 2 each */
  double id0, did, iq0, diq;   /* i_d = id0 + j did, i_q = iq0 + k diq [A], steps > 0 */
  const double *psi_d, *psi_q; /* lambda at grid point (j, k): index k nd + j [Vs] */
} plant_fluxmap_grid_t;

typedef struct plant_fluxmap plant_fluxmap_t; /* opaque, heap (host only) */

/* Builds the forward patches and the inverse map. 0, or -1 with a message
 * in err naming the check and the grid cell. */
int plant_fluxmap_create(const plant_fluxmap_grid_t *g, plant_fluxmap_t **out, char *err,
                         size_t errlen);
void plant_fluxmap_free(plant_fluxmap_t *m);
/* Forward interpolant lambda(i). */
void plant_fluxmap_flux(const plant_fluxmap_t *m, double i_d, double i_q, double *psi_d,
                        double *psi_q);
/* Inverse i(lambda). */
void plant_fluxmap_current(const plant_fluxmap_t *m, double psi_d, double psi_q, double *i_d,
                           double *i_q);
/* jac[r][c] = d i_r / d psi_c at lambda. */
void plant_fluxmap_jacobian(const plant_fluxmap_t *m, double psi_d, double psi_q, double jac[2][2]);
/* Flux at zero current [Vs]. */
void plant_fluxmap_flux0(const plant_fluxmap_t *m, double *psi_d, double *psi_q);
/* The smallest eigenvalue of the (symmetric part of the) incremental
 * inductance matrix over the current grid [H] (step sizing). */
double plant_fluxmap_l_min(const plant_fluxmap_t *m);
/* Flux-grid nodes where the inversion is not unique (the forward Jacobian
 * not positive definite at the solution, or Newton did not converge), with
 * the first one described in msg; and the nodes extrapolated beyond the
 * current grid (outside its image). */
int plant_fluxmap_nonunique(const plant_fluxmap_t *m, char *msg, size_t n);
int plant_fluxmap_extrapolated(const plant_fluxmap_t *m);

#endif
