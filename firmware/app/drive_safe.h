/*
 * drive_safe.h - the safe state while the gates do not modulate: all
 * switches off below the rectifier speed, the active short circuit above
 * it or on DC-link overvoltage (drive_safe.c, docs/faults.md).
 */
#ifndef FLUXDRIVE_DRIVE_SAFE_H
#define FLUXDRIVE_DRIVE_SAFE_H

#include "drive.h"

/* The gates left modulation (a trip, a disable) in this ISR: the next
 * drive_safe_step() chooses between all off and the short. */
void drive_safe_leave_gates(drive_t *drv);
/* The largest stator flux a short may trap without a current beyond
 * i_trip (at configuration; drive_t.asc_psi_max). */
float drive_safe_psi_max(const drive_t *drv);
/* Every ISR in which the gates do not modulate, after the state machine:
 * i the offset-corrected phase currents, s the sample set. */
void drive_safe_step(drive_t *drv, const float i[3], const hal_sample_t *s);

#endif
