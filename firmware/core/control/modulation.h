/*
 * modulation.h - min-max (zero-sequence injection) modulation, equivalent to
 * centred space-vector PWM, normalised by the measured DC-link voltage.
 *
 * Linear range: |v_ab| <= v_dc / sqrt(3). Overmodulation behaviour (defined):
 * a request beyond the linear range is scaled down to the circle of radius
 * v_dc / sqrt(3) keeping its angle (no low-order harmonics, the applied
 * vector is reported so observers and anti-windup see what was applied).
 */
#ifndef FD_CONTROL_MODULATION_H
#define FD_CONTROL_MODULATION_H

#include "math/frames.h"

typedef struct {
  float duty[3];  /* duty cycles of phases a, b, c in [d_min, d_max] */
  ab_t v_applied; /* average voltage vector these duties apply [V] */
  int saturated;  /* 1 when the request was scaled to the linear limit */
} modulation_out_t;

/* Largest voltage amplitude in the linear range of duties [d_min, d_max]:
 * (d_max - d_min) v_dc / sqrt(3). */
float modulation_v_max(float v_dc, float d_min, float d_max);
/* v_ref: alpha-beta voltage reference [V]; v_dc > 0; duties stay inside
 * [d_min, d_max] (0 <= d_min < d_max <= 1, the board's range). A
 * non-positive or non-finite v_dc gives duties at the middle of the range
 * and v_applied = 0. */
modulation_out_t modulation_minmax(ab_t v_ref, float v_dc, float d_min, float d_max);

/* What modulation_minmax_duty() did (its saturated flag: not LINEAR). */
enum { MODULATION_LINEAR = 0, MODULATION_SCALED = 1, MODULATION_SAFE = 2 };
/* The duties of modulation_minmax() alone (the same values), for a caller
 * that rebuilds the applied voltage itself from what the board really
 * applies (the drive: drive_write): no applied vector computed and thrown
 * away every period. SAFE: the middle of the range (no usable v_dc or
 * reference). */
int modulation_minmax_duty(ab_t v_ref, float v_dc, float d_min, float d_max, float duty[3]);

#endif
