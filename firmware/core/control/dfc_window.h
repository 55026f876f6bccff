/*
 * dfc_window.h - the modified PWM pattern of Direct Flux Control (Fabbri
 * 2022, Fig. 2.11): v0 -> v_X at the start of the period for the star-point
 * measurement, then the normal pattern.
 *
 * In fractions of the period, as the thesis's modified edge-aligned
 * pattern v0 -> v_X -> v7 -> ... -> v0: leg X (the test vector v1, v3, v5
 * switches leg a, b, c alone) turns on at t0, the other two at t0 + tw,
 * and each turns off after its duty: off = on + d. The star point is
 * sampled before t0 and at t0 + t_meas (< tw). Every leg keeps its pulse
 * width, so the period-average voltage is exactly the one asked for (the
 * test vector costs no volt-seconds: the current loop does not see it).
 * All rising edges fall in the first half of the period and all falling
 * edges in the second: what a centre-aligned timer does with one compare
 * value per half period (the STM32G4's TIM1, docs/dfc.md "Board"): the
 * rising edges depend only on which leg is X (known periods ahead), the
 * falling ones on the duties. It needs t0 + d_X >= 1/2 and
 * t0 + tw + d <= 1: the duty range is narrowed to
 * [max(d_min, 1/2 - t0), min(d_max, 1 - t0 - tw)] (dfc_window_range),
 * about half the linear voltage range, and the modulation keeps every leg
 * inside it. The current sampled at the valley is in v0 (all low) but no
 * longer at the centre of the zero vector: it differs from the period
 * average by the ripple's asymmetry.
 */
#ifndef FD_CONTROL_DFC_WINDOW_H
#define FD_CONTROL_DFC_WINDOW_H

/* The duty range the window needs inside the board's [d_min, d_max]. */
void dfc_window_range(float t0, float tw, float d_min, float d_max, float *lo, float *hi);

/* Pattern for duties d (inside the range above) with leg `leg` (0, 1, 2)
 * starting at t0: on[x], off[x] in fractions of the period. */
void dfc_window_pattern(const float d[3], unsigned leg, float t0, float tw, float on[3],
                        float off[3]);

/* The current sampled at the start of a period whose pattern is (on, off)
 * differs from what centred pulses give (the period average less half the
 * period's change) by -(v_dc Ts / L) m_x, with the phase moments
 *   m_x = M_x - mean(M),  M_x = int_0^1 (1 - t)(P_x(t) - d_x) dt = d_x (1 - on_x - off_x) / 2
 * (P_x the leg's pulse, d_x its width; M_x = 0 for a centred pulse). The
 * drive adds (v_dc Ts / L) m_x of the pattern in force to the sample. */
void dfc_window_moments(const float on[3], const float off[3], float m[3]);

#endif
