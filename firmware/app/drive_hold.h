/*
 * drive_hold.h - the held start (start_mode 1): a star-point source starts
 * without letting the rotor turn (issue 23, point 3; docs/dfc.md, "The
 * held start").
 *
 * In state align, with zero current, the source measures 2 theta_e at
 * standstill (the DFC window works without current); two opposite voltage
 * pulses along the estimate then show the magnet's polarity by the d-axis
 * saturation: the pulse along the north pole adds to the magnet's flux,
 * meets the lower incremental inductance and builds the larger current
 * (Fabbri 2022, 3.1.3: theta is known from 2 theta only up to pi). The
 * pulses carry no torque (d current along the estimate). Then the run
 * starts from standstill on the estimated angle: 2.44 ms with the
 * gates on and no torque, the only time an active load can move the rotor.
 */
#ifndef FLUXDRIVE_DRIVE_HOLD_H
#define FLUXDRIVE_DRIVE_HOLD_H

#include "drive.h"

enum {
  DRIVE_HOLD_BUSY = 0,
  DRIVE_HOLD_DONE = 1, /* *theta_out: the north pole's angle */
  DRIVE_HOLD_FAIL = 2  /* no angle, or no polarity evidence: the position fault */
};

/* Periods of each phase: the acquisition, then per pulse N_PULSE + N_AVG +
 * 1 and N_ZERO; 39 periods in all, 2.44 ms at 16 kHz */
#define DRIVE_HOLD_N_ACQ   8u   /* zero current: three DFC components, then five updates */
#define DRIVE_HOLD_N_PULSE 3u   /* voltage pulse */
#define DRIVE_HOLD_N_AVG   1u   /* samples of its current averaged */
#define DRIVE_HOLD_N_ZERO  10u  /* the current back to zero (deadbeat, drive_hold.c) */
#define DRIVE_HOLD_K_DB    0.8f /* of the deadbeat step: margin for R, L errors */
/* the pulses' currents must differ by this fraction of their mean */
#define DRIVE_HOLD_EVIDENCE_MIN 0.02f

/* The pulse voltage of the linear R-L model that reaches i_max in
 * DRIVE_HOLD_N_PULSE periods (drive_derive). */
float drive_hold_v_pulse(const drive_config_t *cfg);
void drive_hold_reset(drive_t *drv);
/* One period of the held start: i_ab the measured current, v_max the
 * voltage limit; *v_ab the voltage to apply. */
int drive_hold_step(drive_t *drv, ab_t i_ab, float v_max, ab_t *v_ab, float *theta_out);

#endif
