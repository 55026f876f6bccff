/*
 * plant_dclink.c - DC link. IDEAL: a stiff source, v_dc = v_source always.
 * RC: source v_source behind a series resistance r feeding the link
 * capacitor c; the capacitor voltage is a state integrated with the machine:
 *   C dv/dt = (v_source - v)/R - i_dc,
 * i_dc being the current the inverter draws (sum over legs connected to the
 * positive rail of the phase current; the average model uses the effective
 * duties, so that v_dc i_dc = sum v_x0 i_x holds exactly). A regenerating
 * machine drives i_dc negative and charges the capacitor above v_source: this
 * is what an overvoltage protection trips on. The derivative is inline in
 * plant_internal.h (inner loop).
 */
#include "plant_internal.h"

int plant_dclink_check(const plant_dclink_t *d, const char **field) {
  if (d->kind != PLANT_DC_IDEAL && d->kind != PLANT_DC_RC) {
    *field = "dclink.kind";
    return -1;
  }
  if (!plant_finite_pos(d->v_source)) {
    *field = "dclink.v_source";
    return -1;
  }
  if (d->kind == PLANT_DC_RC) {
    if (!plant_finite_pos(d->r)) {
      *field = "dclink.r";
      return -1;
    }
    if (!plant_finite_pos(d->c)) {
      *field = "dclink.c";
      return -1;
    }
  }
  return 0;
}
