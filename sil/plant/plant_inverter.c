/*
 * plant_inverter.c - inverter parameters and the constants of the
 * average-value dead-time model. The period integrators are in
 * plant_inverter_avg.c (average value, gates on) and plant_inverter_sw.c
 * (switching level, and the diode-only circuit when the gates are off).
 */
#include "plant_internal.h"

#include <math.h>

#define INV_BAND_MIN 5e-3 /* lower bound of the smooth-sign band [A] */

int plant_inverter_check(const plant_inverter_t *inv, double ts, const char **field) {
  if (inv->model != PLANT_INV_AVERAGE && inv->model != PLANT_INV_SWITCHING) {
    *field = "inverter.model";
    return -1;
  }
  if (!(inv->dead_time >= 0.0 && inv->dead_time < 0.25 * ts)) {
    *field = "inverter.dead_time";
    return -1;
  }
  if (inv->substeps < 1 || inv->substeps > 64) {
    *field = "inverter.substeps";
    return -1;
  }
  return 0;
}

/* Smooth-sign band of the average model (plant_inverter_avg.c). Near i = 0
 * the dead-time voltage error acts like a resistance (td/Ts) v_dc / i_band.
 * Explicit RK4 with step h stays monotone (no sign-flipping limit cycle)
 * while h R / L stays well below 2.78; we ask h R / L_min <= 0.5 at
 * v_source, i.e. i_band = 2 (td/Ts) v_source h / L_min, and at least 5 mA.
 * The band is justified physically: in the real inverter the current
 * ripple (of order v_dc Ts / L, far wider than i_band since td << Ts) smears
 * the sign of the current near zero, so the real average error is itself
 * a smooth function of the average current. */
void plant_inverter_init(plant_t *pl) {
  const plant_params_t *p = &pl->p;
  const double h = p->ts / p->inverter.substeps;
  const double lmin = plant_mag_l_min(&pl->aux.mag);
  const double band = 2.0 * pl->aux.kdt * p->dclink.v_source * h / lmin;
  pl->aux.inv_band = 1.0 / fmax(band, INV_BAND_MIN);
}
