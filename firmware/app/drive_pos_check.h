/*
 * drive_pos_check.h - position plausibility: the voltage the drive applied
 * against the machine model's at the position source's angle and speed
 * (drive_pos_check.c, docs/faults.md).
 */
#ifndef FLUXDRIVE_DRIVE_POS_CHECK_H
#define FLUXDRIVE_DRIVE_POS_CHECK_H

#include "drive.h"

/* Once per slow period, before the position source's update, on the
 * telemetry of the last period. Returns DRIVE_FAULT_POSITION when the
 * check trips, else 0. */
uint32_t drive_pos_check(drive_t *drv);

#endif
