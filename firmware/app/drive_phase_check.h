/*
 * drive_phase_check.h - phase balance, checked by the main loop on the
 * telemetry copy (no ISR cost).
 *
 * Over one electrical revolution every phase carries the same mean |i_x|.
 * An open phase (a motor lead off) or a lost one (both switches of a leg
 * off) carries none; the ISR's current-sum check does not see it (the
 * currents still sum to zero). Each fresh telemetry copy with the drive in
 * RUN is one sample (its offset-corrected currents); the angle swept comes
 * from the speed estimate and the ISRs between copies. A revolution is
 * judged when it spans at least DRIVE_PH_MIN_N samples (no aliasing of the
 * means: f_e at most a quarter of the main-loop rate, 250 Hz at 1 kHz) and
 * at most DRIVE_PH_MAX_N (slower: nearly DC currents are legitimately
 * unequal) and its largest mean |i_x| exceeds DRIVE_PH_FLOOR i_max. A phase
 * whose mean |i_x| is below DRIVE_PH_OPEN of the largest in DRIVE_PH_TRIP
 * revolutions in a row (one not judged starts the count again; a transient
 * such as a torque step unbalances one) requests lost_control
 * (drive_request_fault: taken by the next ISR) and counts in `trips`.
 * Not judged: a phase conducting one way only (a switch stuck open): the
 * controller's own transients (a current vector that lags the rotor over a
 * revolution, e.g. the decoupled DFVC after a speed ramp) look the same.
 */
#ifndef FLUXDRIVE_DRIVE_PHASE_CHECK_H
#define FLUXDRIVE_DRIVE_PHASE_CHECK_H

#include <stdint.h>

#define DRIVE_PH_MIN_N 4
#define DRIVE_PH_MAX_N 64
#define DRIVE_PH_TRIP  2
/* below 0.08 of the largest: an open or lost phase gives 0.02 at most (the
 * lost leg's diodes), healthy runs 0.14 at least (the decoupled DFVC's
 * stationary current at light load, tests/python/test_fabbri2022_kf.py) */
#define DRIVE_PH_OPEN  0.08f
#define DRIVE_PH_FLOOR 0.05f

typedef struct {
  float abs[3];      /* sums of |i_x| over the window [A] */
  float angle;       /* electrical angle swept [rad] */
  int32_t n;         /* samples in the window */
  int32_t bad;       /* unbalanced revolutions in a row */
  uint32_t isr_last; /* isr_count of the last sample (0: none) */
  uint32_t trips;    /* lost_control requests made */
} drive_phase_check_t;

struct drive_s;
/* One main-loop period (drive_background, after the telemetry copy). */
void drive_phase_check(struct drive_s *drv);

#endif
