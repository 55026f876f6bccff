/*
 * hal_stm32g4.h - what the STM32G4 HAL offers beyond hal.h, for the board
 * files only (firmware/app sees hal.h alone).
 */
#ifndef FLUXDRIVE_HAL_STM32G4_H
#define FLUXDRIVE_HAL_STM32G4_H

#include <stdbool.h>
#include <stdint.h>

/* Bring-up result bits of hal_stm32g4_init (0 = all fine). */
enum {
  HAL_INIT_ERR_CLOCK = 1u << 0, /* SYSCLK is not the PLL at 170 MHz */
  HAL_INIT_ERR_ADC = 1u << 1,   /* ADC regulator / calibration / ready time-out */
  HAL_INIT_ERR_CAN = 1u << 2,   /* FDCAN did not enter or leave INIT */
  HAL_INIT_ERR_PWM = 1u << 3,   /* TIM1 update could not be aligned to the valley */
  HAL_INIT_ERR_BREAK = 1u << 4, /* DAC3 of the comparator trip did not become ready */
  HAL_INIT_ERR_ISR = 1u << 5    /* no period body given, or no ADC sequence to end a period */
};

/* The application's body of the PWM-period interrupt, registered by
 * hal_stm32g4_start: the HAL calls it once per period, after every ADC
 * injected sequence of the period has ended (adc.c), from the interrupt. */
typedef void (*hal_control_fn)(void);

/* Configure every peripheral (gates off). Returns HAL_INIT_ERR_* bits. */
uint32_t hal_stm32g4_init(void);
/* Start the PWM carrier, align its update, arm the ADC trigger and the
 * PWM-period interrupt, which calls `control` every period. Returns
 * HAL_INIT_ERR_PWM / HAL_INIT_ERR_ISR bits on failure. */
uint32_t hal_stm32g4_start(hal_control_fn control);

/* ISR execution statistics (cycles, overruns): hal_isr_stats() in hal.h. */

/* CAN acceptance: standard and extended identifiers whose bits under
 * `mask` equal node_id, plus the broadcast identifier 0 under the same mask
 * (e.g. mask 0x7F for a CANopen-style node id in the low 7 bits). Every other
 * frame is rejected in hardware. */
void hal_can_set_node_filter(uint32_t node_id, uint32_t mask);
/* true while the controller is bus-off (it restarts by itself). */
bool hal_can_bus_off(void);

/* Start the independent watchdog (cannot be stopped until reset). */
void hal_watchdog_start(uint32_t timeout_ms);

#endif
