/*
 * star_window.h - the Direct Flux Control window on the STM32G4 (boards
 * with BOARD_HAS_STAR_WINDOW: a star-point divider on an ADC input):
 * independent rising and falling edges on TIM1 and the two star-point
 * samples around the test-vector edge (docs/dfc.md, "Board";
 * docs/flashing.md, "Star-point window").
 */
#ifndef FLUXDRIVE_STM32G4_STAR_WINDOW_H
#define FLUXDRIVE_STM32G4_STAR_WINDOW_H

#include <stdbool.h>
#include <stdint.h>

#include "hal.h"

/* TIM1 part (from hal_tim1_init, before the counter starts): OC4REF as
 * TRGO (the valley trigger of the current samples), OC5REF as TRGO2 (the
 * after-sample), updates at both ends of the period (RCR = 0) with a DMA
 * burst of CCR1..CCR3 at each. */
void star_window_tim1_init(void);
/* After the counter started: arms the DMA so that its first burst comes
 * at the next peak. false when the counter could not be caught counting
 * up. */
bool star_window_tim1_start(void);
/* ADC part (from hal_adc_init, after the injected set-up): the star
 * channel's regular conversion on TRGO2. */
void star_window_adc_init(void);
void star_window_adc_start(void);

/* hal_pwm_write for these boards: the pattern's rising edges (first half)
 * and falling edges (second half) into the DMA table; *applied what the
 * timer will do. Written after the carrier peak (too late for the rising
 * edges of the next period) the pattern is applied centred, without the
 * test vector (applied->test_vector = 0, no samples). */
void star_window_write(const hal_pwm_t *p, hal_pwm_t *applied);
/* The star-point samples for hal_adc_read: the window of the period
 * before (before-sample kept from the last ISR, after-sample converted
 * since), timestamped from this period's start (negative). before_raw is
 * this period's injected before-sample in volts w.r.t. the DC midpoint. */
void star_window_read(hal_sample_t *s, float before_now, float t_before);

#endif
