/*
 * plant_magnetics.h - the machine's magnetic model in the plant: the one
 * place where flux linkages (the integration state, rotor frame) and
 * currents are related. Everything else in the plant (both inverter
 * models, the diode logic, the current cache, the sensors) goes through
 * these functions:
 *   plant_mag_current   i_dq(lambda_dq)
 *   plant_mag_jacobian  G = d i_dq / d lambda_dq (the inverse incremental
 *                       inductance matrix) at lambda_dq
 *   plant_mag_flux0     lambda_dq at zero current (the PM flux)
 *   plant_mag_l_min     the smallest incremental inductance (step sizing)
 * PLANT_MAG_LINEAR: lambda_d = Ld i_d + lambda_m, lambda_q = Lq i_q (d on
 * the magnet), inline; with the magnet's saturation (sat > 0) the d current
 * of the flux x = (lambda_d - lambda_m) / Ld is
 *   i_d = x + sat i_sat ln cosh(x / i_sat),  d i_d / d lambda_d = (1 + sat tanh(x / i_sat)) / Ld
 * (monotonic for sat < 1): a d current along the magnet (x > 0) meets an
 * incremental inductance down to Ld / (1 + sat), one against it up to
 * Ld / (1 - sat): the iron the magnet already half saturates (Fabbri 2022,
 * 3.1.3: the magnet's polarity, which the 2 theta_e of the star point
 * cannot tell, shows in the d-axis saturation; the held start,
 * docs/dfc.md). The star point's (3.3) matrix keeps the unsaturated
 * inductances. PLANT_MAG_MAP: a flux map with saturation and
 * cross-saturation, its inverse i(lambda) built at load time
 * (plant_fluxmap.h), behind the same four functions.
 */
#ifndef FD_PLANT_MAGNETICS_H
#define FD_PLANT_MAGNETICS_H

#include <math.h>
#include <stddef.h>

#include "plant_fluxmap.h"

typedef enum { PLANT_MAG_LINEAR = 0, PLANT_MAG_MAP } plant_mag_kind_t;

typedef struct {
  plant_mag_kind_t kind;
  double lambda_m;            /* lambda_d at zero current [Vs] */
  double inv_ld, inv_lq;      /* 1/Ld, 1/Lq [1/H] */
  double sat, i_sat;          /* the magnet's saturation (header; sat 0: none) */
  const plant_fluxmap_t *map; /* PLANT_MAG_MAP */
} plant_mag_t;

/* The model of a linear machine (ld, lq > 0). */
static inline plant_mag_t plant_mag_linear(double ld, double lq, double lambda_m) {
  plant_mag_t g = {PLANT_MAG_LINEAR, lambda_m, 1.0 / ld, 1.0 / lq, 0.0, 1.0, NULL};
  return g;
}

/* The model of a flux-map machine. */
static inline plant_mag_t plant_mag_map(const plant_fluxmap_t *map) {
  plant_mag_t g = {PLANT_MAG_MAP, 0.0, 0.0, 0.0, 0.0, 1.0, map};
  return g;
}

static inline void plant_mag_current(const plant_mag_t *g, double lambda_d, double lambda_q,
                                     double *i_d, double *i_q) {
  if (g->kind == PLANT_MAG_MAP) {
    plant_fluxmap_current(g->map, lambda_d, lambda_q, i_d, i_q);
    return;
  }
  const double x = (lambda_d - g->lambda_m) * g->inv_ld;
  /* ln cosh u = |u| + log1p(exp(-2 |u|)) - ln 2: no overflow */
  const double u = fabs(x / g->i_sat);
  *i_d = g->sat > 0.0 ? x + g->sat * g->i_sat * (u + log1p(exp(-2.0 * u)) - 0.6931471805599453) : x;
  *i_q = lambda_q * g->inv_lq;
}

/* jac[r][c] = d i_r / d lambda_c, r, c in {d, q}. */
static inline void plant_mag_jacobian(const plant_mag_t *g, double lambda_d, double lambda_q,
                                      double jac[2][2]) {
  if (g->kind == PLANT_MAG_MAP) {
    plant_fluxmap_jacobian(g->map, lambda_d, lambda_q, jac);
    return;
  }
  jac[0][0] =
      g->sat > 0.0
          ? g->inv_ld * (1.0 + g->sat * tanh((lambda_d - g->lambda_m) * g->inv_ld / g->i_sat))
          : g->inv_ld;
  jac[0][1] = 0.0;
  jac[1][0] = 0.0;
  jac[1][1] = g->inv_lq;
}

static inline void plant_mag_flux0(const plant_mag_t *g, double *lambda_d, double *lambda_q) {
  if (g->kind == PLANT_MAG_MAP) {
    plant_fluxmap_flux0(g->map, lambda_d, lambda_q);
    return;
  }
  *lambda_d = g->lambda_m;
  *lambda_q = 0.0;
}

static inline double plant_mag_l_min(const plant_mag_t *g) {
  if (g->kind == PLANT_MAG_MAP) {
    return plant_fluxmap_l_min(g->map);
  }
  const double gd = g->inv_ld * (1.0 + g->sat);
  const double gmax = gd > g->inv_lq ? gd : g->inv_lq;
  return 1.0 / gmax;
}

#endif
