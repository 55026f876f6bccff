/*
 * plant_dclink.c - DC link. IDEAL: a stiff source, v_dc = v_source always.
 * RC: source v_source behind a series resistance r feeding the link
 * capacitor c; the capacitor voltage is a state integrated with the machine:
 *   C dv/dt = (v_source - v)/R - i_dc,
 * i_dc being the current the inverter draws (sum over legs connected to the
 * positive rail of the phase current; the average model uses the effective
 * duties, so that v_dc i_dc = sum v_x0 i_x holds exactly). A regenerating
 * machine drives i_dc negative and charges the capacitor above v_source: this
 * is what an overvoltage protection trips on. RECTIFIER: the same, but the
 * source feeds through a diode ((v_source - v)/r >= 0): a regenerating
 * machine charges c without limit unless a braking chopper (r_chop) or the
 * drive (active short circuit) stops it. The derivative is inline in
 * plant_internal.h (inner loop).
 */
#include "plant_internal.h"

int plant_dclink_check(const plant_dclink_t *d, const char **field) {
  if (d->kind != PLANT_DC_IDEAL && d->kind != PLANT_DC_RC && d->kind != PLANT_DC_RECTIFIER) {
    *field = "dclink.kind";
    return -1;
  }
  if (!plant_finite_pos(d->v_source)) {
    *field = "dclink.v_source";
    return -1;
  }
  if (d->kind != PLANT_DC_IDEAL) {
    if (!plant_finite_pos(d->r)) {
      *field = "dclink.r";
      return -1;
    }
    if (!plant_finite_pos(d->c)) {
      *field = "dclink.c";
      return -1;
    }
  }
  if (!plant_finite_nonneg(d->r_chop)) {
    *field = "dclink.r_chop";
    return -1;
  }
  if (d->r_chop > 0.0) {
    if (d->kind == PLANT_DC_IDEAL) {
      *field = "dclink.r_chop"; /* a stiff link needs no chopper */
      return -1;
    }
    if (!(plant_finite_pos(d->v_chop_off) && d->v_chop_off < d->v_chop_on &&
          d->v_chop_on < 1e300)) {
      *field = "dclink.v_chop_on";
      return -1;
    }
  }
  return 0;
}

void plant_dclink_chopper(plant_t *pl) {
  const plant_dclink_t *d = &pl->p.dclink;
  if (!(d->r_chop > 0.0)) {
    return;
  }
  if (pl->v_dc > d->v_chop_on) {
    pl->aux.chop_on = 1;
  } else if (pl->v_dc < d->v_chop_off) {
    pl->aux.chop_on = 0;
  }
  pl->aux.g_chop = pl->aux.chop_on ? 1.0 / d->r_chop : 0.0;
}
