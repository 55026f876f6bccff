/*
 * protect/runaway.h - the run-away check (issue 23, point 2;
 * docs/faults.md), an owned part of the drive's protections
 * (docs/architecture.md, "Adding a protection").
 *
 * Whatever the position source says, the rotor must not run away from the
 * speed reference against the torque the speed loop asks. The condition,
 * each speed-loop period: the speed is off the (ramped) reference by more
 * than PROTECT_RA_MARGIN |w_ref| + PROTECT_RA_FLOOR speed_max, and the
 * loop's torque pushes it back (torque x error < 0). Held for
 * PROTECT_RA_TIME without a break, it trips lost_control (lc_cause
 * DRIVE_LC_RUNAWAY) if the speed itself has moved meanwhile by
 * PROTECT_RA_FLOOR speed_max further from the reference - the mean over
 * the window's last quarter against the mean over its first, not two
 * single samples of a noisy estimate (a PLL's speed swinging about a rotor
 * that heads for its reference tripped it on a drawn machine) - : the
 * rotor went away against the torque (a wrong polarity or angle turns the
 * torque against the loop). A speed that moves back (a healthy drive
 * braking to its reference, a reversal, a load step the loop catches) or
 * that the reference outruns (a ramp faster than the torque the voltage
 * allows) starts the window again. Once per speed-loop period (1 kHz: the
 * ISR of every slow_div-th period, after the speed loop), a few flops.
 */
#ifndef FLUXDRIVE_PROTECT_RUNAWAY_H
#define FLUXDRIVE_PROTECT_RUNAWAY_H

#include <stdint.h>

#define PROTECT_RA_MARGIN 0.2f  /* of |w_ref| */
#define PROTECT_RA_FLOOR  0.02f /* of speed_max: the margin's floor, and the growth */
#define PROTECT_RA_TIME   0.02f /* s */

typedef struct {
  uint32_t n;   /* speed-loop periods the condition has held */
  float w0, w1; /* the speed's sums over the window's first and last quarter [rad/s] */
  /* of the parameter set in force (protect_ra_configure) */
  float floor;    /* PROTECT_RA_FLOOR speed_max [rad/s] */
  uint32_t n_win; /* speed-loop periods in the window */
  uint32_t q;     /* ... in its quarter */
} protect_ra_t;

/* What the check reads each speed-loop period. */
typedef struct {
  float w;      /* the speed averaged over the period [rad/s] */
  float w_ref;  /* the ramped reference [rad/s] */
  float torque; /* the speed loop's torque [N m] */
} protect_ra_view_t;

/* speed_max [rad/s], t_loop the speed loop's period (slow_div Ts) [s]. */
void protect_ra_configure(protect_ra_t *p, float speed_max, float t_loop);
void protect_ra_reset(protect_ra_t *p);
/* One speed-loop period: DRIVE_LC_RUNAWAY when it trips, else 0. */
uint32_t protect_ra_step(protect_ra_t *p, const protect_ra_view_t *v);

#endif
