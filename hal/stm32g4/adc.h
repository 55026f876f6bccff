/* adc.h - ADC1/ADC2 injected sequences triggered by TIM1 TRGO (RM0440
 * section 21), plus the internal OPAMP PGAs where the board uses them. */
#ifndef FLUXDRIVE_STM32G4_ADC_H
#define FLUXDRIVE_STM32G4_ADC_H

#include <stdbool.h>
#include <stdint.h>

#include "hal_stm32g4.h"

/* Power up, calibrate (ADCAL, single ended) and enable ADC1 and ADC2,
 * program the injected sequences from the board table. false on a
 * time-out (regulator, calibration or ADRDY). */
bool hal_adc_init(void);
/* Arm the injected conversions (JADSTART) and the JEOS interrupt of each
 * ADC in use; `control` runs once per period, at the last end (adc.c).
 * false when control is NULL or no ADC has an injected sequence. */
bool hal_adc_start(hal_control_fn control);

#endif
