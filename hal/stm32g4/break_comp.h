/* break_comp.h - the comparator over-current trip: the board's COMPx on the
 * shunt signals against DAC3 into the TIM1 break (RM0440 sections 22, 24,
 * 28.3.19), for boards with BOARD_HAS_BREAK_COMP. */
#ifndef FLUXDRIVE_STM32G4_BREAK_COMP_H
#define FLUXDRIVE_STM32G4_BREAK_COMP_H

#include <stdbool.h>
#include <stdint.h>

/* DAC3 code (12 bit, VDDA reference) at which the comparators trip for a
 * phase current of i_trip [A] in the direction where the board's current
 * signal rises; clamped to 0..4095. */
uint32_t hal_break_comp_dac_code(float i_trip);
/* The current [A] a DAC3 code trips at (the inverse, for the docs). */
float hal_break_comp_trip_current(uint32_t code);
/* TIM1_AF1 break-source bits of the board's comparators (BKCMPxE; the
 * polarity bits BKCMPxP stay 0: with BKP = 1 a high comparator output is a
 * break). 0 on boards without them. Written by hal_tim1_init before LOCK. */
uint32_t hal_break_comp_af1(void);
/* Clock, program and enable DAC3 and the comparators, then lock their
 * CSRs. false when a DAC3 channel did not report ready. Call after the
 * op-amp and analog pin set-up (hal_adc_init). */
bool hal_break_comp_init(void);

#endif
