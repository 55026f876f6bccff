/*
 * plant_machine.c - PM synchronous machine in the rotor frame, d on the
 * magnet. State: rotor-frame flux linkages; the currents follow from the
 * magnetic model (plant_magnetics.h; linear: lambda_d = Ld i_d + lambda_m,
 * lambda_q = Lq i_q, SPM Ld = Lq, IPM Ld < Lq):
 *   d lambda_d/dt = v_d - Rs i_d + w_e lambda_q
 *   d lambda_q/dt = v_q - Rs i_q - w_e lambda_d
 *   T_e = 1.5 p (lambda_d i_q - lambda_q i_d),  theta_e = p theta_m.
 * Amplitude-invariant Clarke/Park: the alpha axis is phase a, peak phase
 * current = |i_dq|. The derivatives themselves are evaluated inside the
 * inverter models (plant_inverter_avg.c, plant_inverter_sw.c) where the
 * applied voltage is known; only the flux -> current map (a flux map can
 * replace it later) and the shared transforms live here.
 */
#include "plant_internal.h"

#include <math.h>

int plant_machine_check(const plant_machine_t *m, const char **field) {
  const char *bad = NULL;
  if (m->pole_pairs < 1 || m->pole_pairs > 1000) {
    bad = "machine.pole_pairs";
  } else if (!plant_finite_pos(m->rs)) {
    bad = "machine.rs";
  } else if (m->map != NULL) {
    /* a flux map: validated and inverted by plant_fluxmap_create */
  } else if (!plant_finite_pos(m->ld)) {
    bad = "machine.ld";
  } else if (!plant_finite_pos(m->lq)) {
    bad = "machine.lq";
  } else if (!plant_finite_nonneg(m->lambda_m)) {
    bad = "machine.lambda_m";
  } else if (!(m->ld_sat >= 0.0 && m->ld_sat <= 0.5)) {
    bad = "machine.ld_sat";
  } else if (m->ld_sat > 0.0 && !plant_finite_pos(m->i_sat)) {
    bad = "machine.i_sat";
  } else if (m->aniso.enabled && !plant_aniso_ok(m)) {
    bad = "machine.star_m0"; /* the (3.3) matrix is not positive definite */
  }
  if (bad == NULL && m->map != NULL && m->aniso.enabled) {
    bad = "machine.star_m0"; /* the star-point model needs a linear machine */
  }
  if (bad != NULL) {
    *field = bad;
    return -1;
  }
  return 0;
}

void plant_machine_cur_fill(const plant_t *pl, plant_cur_cache_t *c, double co, double si) {
  c->key[0] = pl->lambda_d;
  c->key[1] = pl->lambda_q;
  c->key[2] = pl->theta_m;
  c->th_e = pl->p.machine.pole_pairs * pl->theta_m;
  double id, iq;
  plant_mag_current(&pl->aux.mag, pl->lambda_d, pl->lambda_q, &id, &iq);
  const double ia = id * co - iq * si, ib = id * si + iq * co;
  c->c = co;
  c->s = si;
  c->i_dq[0] = id;
  c->i_dq[1] = iq;
  c->i_abc[0] = ia;
  c->i_abc[1] = -0.5 * ia + PLANT_SQRT3_2 * ib;
  c->i_abc[2] = -0.5 * ia - PLANT_SQRT3_2 * ib;
}

void plant_machine_cur_compute(const plant_t *pl, plant_cur_cache_t *c) {
  const double th_e = pl->p.machine.pole_pairs * pl->theta_m;
  plant_machine_cur_fill(pl, c, cos(th_e), sin(th_e));
}

/* Projects the flux state so that phase `leg`'s current is zero, moving
 * lambda_dq along the gradient of that current (smallest change), a Newton
 * step: exact for the linear model. Used when a free-wheeling diode blocks:
 * i_x = p . i_dq(lambda) with p = R(-theta_e) c_x, gradient k = G^T p,
 * G = d i / d lambda (plant_magnetics.h); c, s: cos and sin of the
 * electrical angle pole_pairs * x[X_TH] (the caller's, carried). */
void plant_machine_zero_phase_current_cs(const plant_t *pl, double *x, int leg, double c,
                                         double s) {
  static const double cx[3][2] = {{1.0, 0.0}, {-0.5, PLANT_SQRT3_2}, {-0.5, -PLANT_SQRT3_2}};
  const double p1 = cx[leg][0] * c + cx[leg][1] * s;
  const double p2 = -cx[leg][0] * s + cx[leg][1] * c;
  double id, iq, G[2][2];
  plant_mag_current(&pl->aux.mag, x[X_LD], x[X_LQ], &id, &iq);
  plant_mag_jacobian(&pl->aux.mag, x[X_LD], x[X_LQ], G);
  const double k1 = G[0][0] * p1 + G[1][0] * p2, k2 = G[0][1] * p1 + G[1][1] * p2;
  const double ix = p1 * id + p2 * iq;
  const double n2 = k1 * k1 + k2 * k2;
  x[X_LD] -= ix * k1 / n2;
  x[X_LQ] -= ix * k2 / n2;
}
