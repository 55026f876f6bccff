/*
 * plant_mech.c - mechanics.
 * FREE mode:    J dw/dt = T_e - B w - T_load(t),  dtheta_m/dt = w.
 *   Sign convention: mech.load_torque is a signed torque SUBTRACTED from the
 *   electromagnetic torque (positive = braking a positively turning rotor,
 *   i.e. a motoring load for w > 0; negative = a load that drives the
 *   rotor forward). It does not flip with the speed sign: describe a load
 *   that always opposes motion by giving it the sign of the speed.
 *   Cogging torque (FREE mode; mech.cog_amp 0: none): the magnets' pull on
 *   the stator teeth at zero current, a torque of the rotor angle alone,
 *   T_cog = A sin(N theta_m + phi), N periods per mechanical turn (the
 *   least common multiple of slots and poles for the fundamental; one
 *   harmonic), added to T_e in both inverter models' mechanics and in the
 *   net torque the passive load's Coulomb friction holds at standstill
 *   (plant_faults.c). It is not part of T_e (plant_state_t.torque): the
 *   current does not carry it. Its stiffness A N sets a mode
 *   sqrt(A N / J) that the integration steps cover (plant_substeps_mech).
 * IMPOSED mode (dynamometer): w = mech.speed(t) exactly, theta_m is the
 *   integral of the profile (RK4 quadrature, exact for constant and ramp
 *   profiles except within the step that holds a ramp corner or a step); J, B and the load are not
 * used. Rotor angle and speed are integrated in the same RK4 as the flux linkages (inline
 * derivative in plant_internal.h).
 */
#include "plant_internal.h"

#include <math.h>
#include <string.h>

int plant_mech_check(const plant_mech_t *m, const char **field) {
  static const char *const load_names[] = {
      "mech.load_torque.n",         "mech.load_torque.term.kind", "mech.load_torque.term.value",
      "mech.load_torque.term.t0",   "mech.load_torque.term.t1",   "mech.load_torque.term.freq",
      "mech.load_torque.term.phase"};
  static const char *const speed_names[] = {
      "mech.speed.n",       "mech.speed.term.kind", "mech.speed.term.value", "mech.speed.term.t0",
      "mech.speed.term.t1", "mech.speed.term.freq", "mech.speed.term.phase"};
  static const char *const member[] = {"n",       "term.kind", "term.value", "term.t0",
                                       "term.t1", "term.freq", "term.phase"};
  const char *bad = NULL;
  if (m->mode != PLANT_MECH_FREE && m->mode != PLANT_MECH_IMPOSED) {
    bad = "mech.mode";
  } else if (!plant_finite_pos(m->j)) {
    bad = "mech.j";
  } else if (!plant_finite_nonneg(m->b)) {
    bad = "mech.b";
  } else if (!isfinite(m->theta0)) {
    bad = "mech.theta0";
  } else if (!isfinite(m->omega0)) {
    bad = "mech.omega0";
  } else if (!(fabs(m->cog_amp) <= PLANT_COG_AMP_MAX)) {
    bad = "mech.cog_amp";
  } else if (m->cog_amp != 0.0 && (m->cog_order < 1 || m->cog_order > PLANT_COG_ORDER_MAX)) {
    bad = "mech.cog_order";
  } else if (!(fabs(m->cog_phase) <= PLANT_COG_PHASE_MAX)) {
    bad = "mech.cog_phase";
  }
  for (int k = 0; bad == NULL && k < 2; k++) {
    const char *sub = NULL;
    if (profile_check(k == 0 ? &m->load_torque : &m->speed, &sub) != 0) {
      for (int i = 0; i < 7; i++) {
        if (strcmp(sub, member[i]) == 0) {
          bad = k == 0 ? load_names[i] : speed_names[i];
        }
      }
      if (bad == NULL) {
        bad = k == 0 ? "mech.load_torque" : "mech.speed";
      }
    }
  }
  if (bad != NULL) {
    *field = bad;
    return -1;
  }
  return 0;
}

/* End of an integration step at t_end: the imposed speed is the profile
 * value (exact, no integration error). */
void plant_mech_end_step(const plant_t *pl, double *x, double t_end) {
  if (pl->p.mech.mode == PLANT_MECH_IMPOSED) {
    x[X_W] = profile_eval(&pl->p.mech.speed, t_end);
  }
}
