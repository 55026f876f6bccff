/*
 * plant_faults.c - plant-parameter faults the controller is not told of
 * (plant.h plant_faults_t): winding temperature (R_s), PM demagnetisation
 * (lambda_m), DC-link capacitor loss (C) and a passive load (Coulomb and
 * viscous friction).
 *
 * Each profile is evaluated at the period start and held over the period,
 * so the RK4 stages see one set of parameters (the integrator stays smooth)
 * and the inner loops read the same members as without faults:
 * p.machine.rs, aux.mag.lambda_m, aux.inv_c, p.mech.b; the Coulomb torque
 * enters through the mechanical input (aux.fric, plant_internal.h).
 *
 * Demagnetisation keeps the flux linkages (the state) continuous: a PM
 * flux that drops by d lambda moves i_d by d lambda / L_d, as Faraday's
 * law requires of a winding with finite voltage. A flux-map machine's PM
 * flux is inside its map (saturation and cross-saturation with it): it is
 * refused, a demagnetised map is another map.
 *
 * Passive load: friction opposes the motion and never drives the rotor.
 * Moving at the period start (w != 0): Coulomb torque sign(w) T_c over the
 * period; if the speed crosses zero within it, the friction stopped the
 * rotor: w = 0 at the end. At standstill: the net torque on the rotor
 * (electromagnetic less the active load, at the start) is held by the
 * friction up to T_c (the rotor stays, its angle unchanged); beyond T_c the
 * rotor breaks away in the direction of the net torque against T_c. A
 * motion reversed by an active load is delayed by at most one period (the
 * rotor rests for the period in which it crosses zero).
 */
#include "plant_internal.h"

#include <math.h>

static int check_one(const profile_t *pr, double lo_min, int lo_open, double hi_max,
                     const char *name, const char **field) {
  if (pr->n == 0) {
    return 0;
  }
  double lo, hi;
  profile_bounds(pr, &lo, &hi);
  if (profile_check(pr, NULL) != 0 || !(lo_open ? lo > lo_min : lo >= lo_min) || !(hi <= hi_max)) {
    *field = name;
    return -1;
  }
  return 0;
}

int plant_faults_check(const plant_params_t *p, const char **field) {
  const plant_faults_t *f = &p->faults;
  if (check_one(&f->rs_scale, 0.0, 1, PLANT_RS_SCALE_MAX, "faults.rs_scale", field) ||
      check_one(&f->lambda_m_scale, 0.0, 0, PLANT_LAMBDA_M_SCALE_MAX, "faults.lambda_m_scale",
                field) ||
      check_one(&f->c_scale, 0.0, 1, PLANT_C_SCALE_MAX, "faults.c_scale", field) ||
      check_one(&f->star_shift, -PLANT_STAR_SHIFT_MAX, 0, PLANT_STAR_SHIFT_MAX, "faults.star_shift",
                field) ||
      check_one(&f->coulomb, 0.0, 0, 1e6, "faults.coulomb", field) ||
      check_one(&f->viscous, 0.0, 0, 1e6, "faults.viscous", field)) {
    return -1;
  }
  if (f->lambda_m_scale.n > 0 && p->machine.map != NULL) {
    *field = "faults.lambda_m_scale";
    return -1;
  }
  if (f->c_scale.n > 0 && p->dclink.kind == PLANT_DC_IDEAL) {
    *field = "faults.c_scale";
    return -1;
  }
  if ((f->coulomb.n > 0 || f->viscous.n > 0) && p->mech.mode != PLANT_MECH_FREE) {
    *field = f->coulomb.n > 0 ? "faults.coulomb" : "faults.viscous";
    return -1;
  }
  return 0;
}

void plant_faults_init(plant_t *pl) {
  const plant_faults_t *f = &pl->p.faults;
  plant_aux_t *a = &pl->aux;
  a->faults_on = f->rs_scale.n > 0 || f->lambda_m_scale.n > 0 || f->c_scale.n > 0 ||
                 f->coulomb.n > 0 || f->viscous.n > 0 || f->star_shift.n > 0;
  a->rs0 = pl->p.machine.rs;
  a->lambda_m0 = a->mag.lambda_m;
  a->inv_c0 = a->inv_c;
  a->b0 = pl->p.mech.b;
  a->fric = 0.0;
  a->fric_dir = 1;
  a->th_start = pl->theta_m;
}

void plant_faults_period_start(plant_t *pl) {
  plant_aux_t *a = &pl->aux;
  if (!a->faults_on) {
    return;
  }
  const plant_faults_t *f = &pl->p.faults;
  const double t = pl->t;
  if (f->rs_scale.n > 0) {
    pl->p.machine.rs = a->rs0 * profile_eval(&f->rs_scale, t);
  }
  if (f->lambda_m_scale.n > 0) {
    const double lm = a->lambda_m0 * profile_eval(&f->lambda_m_scale, t);
    if (lm != a->mag.lambda_m) {
      a->mag.lambda_m = lm;
      a->cur.key[0] = NAN; /* the cached currents belong to the old PM flux */
    }
  }
  if (f->c_scale.n > 0) {
    a->inv_c = a->inv_c0 / profile_eval(&f->c_scale, t);
  }
  if (f->star_shift.n > 0) {
    pl->p.machine.aniso.shift = profile_eval(&f->star_shift, t);
  }
  if (f->viscous.n > 0) {
    pl->p.mech.b = a->b0 + profile_eval(&f->viscous, t);
  }
  if (f->coulomb.n == 0) {
    return;
  }
  const double tc = profile_eval(&f->coulomb, t);
  a->fric = 0.0;
  a->th_start = pl->theta_m;
  if (pl->omega_m > 0.0 || pl->omega_m < 0.0) {
    a->fric_dir = pl->omega_m > 0.0 ? 1 : -1;
    a->fric = a->fric_dir * tc;
    return;
  }
  /* standstill: the net torque the friction has to hold */
  const plant_cur_cache_t *c = plant_machine_cur(pl);
  const double te =
      1.5 * pl->p.machine.pole_pairs * (pl->lambda_d * c->i_dq[1] - pl->lambda_q * c->i_dq[0]);
  double net = te - plant_mech_input(pl, t); /* aux.fric is 0 here */
  if (pl->p.mech.cog_amp != 0.0) {           /* the cogging torque (plant_mech.c) */
    const plant_mech_t *me = &pl->p.mech;
    const double cog[3] = {me->cog_amp, (double)me->cog_order, me->cog_phase};
    net += plant_mech_cogging(cog, pl->theta_m);
  }
  if (fabs(net) <= tc) {
    a->fric_dir = 0;
    a->fric = net; /* held */
  } else {
    a->fric_dir = net > 0.0 ? 1 : -1;
    a->fric = a->fric_dir * tc;
  }
}

void plant_faults_period_end(plant_t *pl, double *x, double cs_end[2]) {
  plant_aux_t *a = &pl->aux;
  if (pl->p.faults.coulomb.n == 0) {
    return;
  }
  if (a->fric_dir == 0) { /* held: no motion over the period */
    x[X_W] = 0.0;
    x[X_TH] = a->th_start;
    cs_end[0] = NAN; /* the carried cos/sin belong to the integrated angle */
  } else if (x[X_W] * a->fric_dir < 0.0) {
    x[X_W] = 0.0; /* the friction stopped the rotor: it cannot reverse it */
  }
}
