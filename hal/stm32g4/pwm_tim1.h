/* pwm_tim1.h - TIM1 centre-aligned complementary PWM with dead time and
 * hardware break (RM0440 section 28). */
#ifndef FLUXDRIVE_STM32G4_PWM_TIM1_H
#define FLUXDRIVE_STM32G4_PWM_TIM1_H

#include <stdbool.h>
#include <stdint.h>

/* BDTR.DTG encoding of a dead time [ns] for a timer clock f_tim [Hz]
 * (t_DTS = 1/f_tim, CKD = 00), rounded up; 0xFF when out of range. */
uint32_t hal_tim1_dtg(uint32_t dead_ns, uint32_t f_tim);
/* Configure TIM1 and its pins; gates stay off (MOE = 0). */
void hal_tim1_init(void);
/* Start the counter and align the update event (RCR = 1) to the
 * underflow = carrier valley. Returns false when it could not verify the
 * alignment. Call with interrupts disabled, before the ADC is started. */
bool hal_tim1_start(void);
/* Update flag (set at every valley) for the ISR overrun check. */
void hal_tim1_clear_update(void);
bool hal_tim1_update_pending(void);

#endif
