/*
 * dfc_window.h - the modified PWM pattern of Direct Flux Control (Fabbri
 * 2022, Fig. 2.11): v0 -> v_X at the start of the period for the star-point
 * measurement, then the normal pattern.
 *
 * In fractions of the period: leg X (the test vector v1, v3, v5 switches
 * leg a, b, c alone) turns on at t0; the other legs keep their centred
 * pulses but start no earlier than t0 + tw, so v_X holds over [t0, t0 + tw)
 * and the star point is sampled before t0 and at t0 + t_meas (< tw).
 * Every leg keeps its pulse width: leg X's pulse is only moved to start
 * at t0, so the period-average voltage is exactly the one asked for (the
 * test vector costs no volt-seconds: the current loop does not see it).
 * It needs d_X >= tw (v_X must last past the sample) and, for the others,
 * t0 + tw + d <= 1: the duty range is narrowed to
 * [max(d_min, tw), min(d_max, 1 - t0 - tw)] (dfc_window_range) and the
 * modulation keeps every leg inside it.
 */
#ifndef FD_CONTROL_DFC_WINDOW_H
#define FD_CONTROL_DFC_WINDOW_H

/* The duty range the window needs inside the board's [d_min, d_max]. */
void dfc_window_range(float t0, float tw, float d_min, float d_max, float *lo, float *hi);

/* Pattern for duties d (inside the range above) with leg `leg` (0, 1, 2)
 * starting at t0: on[x], off[x] in fractions of the period. */
void dfc_window_pattern(const float d[3], unsigned leg, float t0, float tw, float on[3],
                        float off[3]);

#endif
