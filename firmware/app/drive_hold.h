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
 * starts from standstill on the estimated angle: 2.44 to 3.25 ms with
 * the gates on and no torque, the only time an active load can move the rotor.
 */
#ifndef FLUXDRIVE_DRIVE_HOLD_H
#define FLUXDRIVE_DRIVE_HOLD_H

#include "drive.h"

enum {
  DRIVE_HOLD_BUSY = 0,
  DRIVE_HOLD_DONE = 1, /* *theta_out: the north pole's angle */
  DRIVE_HOLD_FAIL = 2  /* no angle, or no polarity evidence: the position fault */
};

/* Periods of each phase: the acquisition, then per pulse n_pulse + N_AVG +
 * 1 and n_zero (drive_hold.c); 39 periods in all, 2.44 ms at 16 kHz, on
 * fabbri2022_t51 (n_pulse 3), up to 8 + 2 (8 + 2 + 12) = 52, 3.25 ms */
#define DRIVE_HOLD_N_ACQ       8u /* zero current: three DFC components, then five updates */
#define DRIVE_HOLD_N_PULSE_MIN 2u /* voltage pulse, periods (pulse_periods) */
#define DRIVE_HOLD_N_PULSE_MAX 8u
#define DRIVE_HOLD_N_AVG       1u   /* samples of its current averaged */
#define DRIVE_HOLD_N_ZERO      10u  /* at least, the current back to zero (deadbeat) */
#define DRIVE_HOLD_K_DB        0.8f /* of the deadbeat step: margin for R, L errors */
/* the pulses' currents must differ by this fraction of their mean */
#define DRIVE_HOLD_EVIDENCE_MIN 0.02f

void drive_hold_reset(drive_t *drv);
/* One period of the held start: i_ab the measured current, v_max the
 * voltage limit; *v_ab the voltage to apply. */
int drive_hold_step(drive_t *drv, ab_t i_ab, float v_max, ab_t *v_ab, float *theta_out);

#endif
