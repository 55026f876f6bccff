/* clock.h - system clock: 170 MHz from the PLL in range 1 boost mode. */
#ifndef FLUXDRIVE_STM32G4_CLOCK_H
#define FLUXDRIVE_STM32G4_CLOCK_H

#include <stdint.h>

/* HSE (board's BOARD_HSE_HZ, 0 = HSI16) -> PLL -> SYSCLK = HCLK = PCLK1 =
 * PCLK2 = 170 MHz. Called once from the reset handler. Returns 0, or -1 if
 * an oscillator or the PLL did not become ready (then SYSCLK stays HSI16). */
int hal_clock_init(void);
/* Busy wait of at least n core cycles (for start-up delays only). */
void hal_delay_cycles(uint32_t n);

#endif
