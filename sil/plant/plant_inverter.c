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
  /* the device drops (plant.h): thresholds and resistances of power
   * devices, each within [0, PLANT_V_DROP_MAX] and [0, PLANT_R_DROP_MAX] */
  const char *bad =
      !(inv->v_th_sw >= 0.0 && inv->v_th_sw <= PLANT_V_DROP_MAX)       ? "inverter.v_th_sw"
      : !(inv->r_on_sw >= 0.0 && inv->r_on_sw <= PLANT_R_DROP_MAX)     ? "inverter.r_on_sw"
      : !(inv->v_f_diode >= 0.0 && inv->v_f_diode <= PLANT_V_DROP_MAX) ? "inverter.v_f_diode"
      : !(inv->r_diode >= 0.0 && inv->r_diode <= PLANT_R_DROP_MAX)     ? "inverter.r_diode"
                                                                       : NULL;
  if (bad != NULL) {
    *field = bad;
    return -1;
  }
  return 0;
}

/* Smooth-sign band of the average model (plant_inverter_avg.c). Near i = 0
 * the dead-time voltage error acts like a resistance (td/Ts) v_dc / i_band,
 * and a device threshold v_th like v_th / i_band (both models take the
 * thresholds in over this band, plant_inverter_sw.c), so the band counts
 * the larger threshold v_max as well: i_band = 2 ((td/Ts) v_source + v_max)
 * h / L_min (v_max = 0 without drops: the band as before).
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
  const double vmax = fmax(p->inverter.v_th_sw, p->inverter.v_f_diode);
  const double band = 2.0 * (pl->aux.kdt * p->dclink.v_source + vmax) * h / lmin;
  pl->aux.inv_band = 1.0 / fmax(band, INV_BAND_MIN);
  pl->aux.drops = p->inverter.v_th_sw > 0.0 || p->inverter.r_on_sw > 0.0 ||
                  p->inverter.v_f_diode > 0.0 || p->inverter.r_diode > 0.0;
}
