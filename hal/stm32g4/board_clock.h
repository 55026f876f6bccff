/*
 * board_clock.h - the clock every STM32G4 board of fluxdrive runs at, and
 * what the PWM timer makes of it. Included by board.h and by the SIL's
 * board presets (sil/runner/board_*.c), so that the SIL models the
 * board's timer resolution from the same numbers.
 */
#ifndef FLUXDRIVE_STM32G4_BOARD_CLOCK_H
#define FLUXDRIVE_STM32G4_BOARD_CLOCK_H

#define BOARD_SYSCLK_HZ 170000000u
/* TIM1 centre-aligned at f_pwm: ARR = f_tim / (2 f_pwm) compare steps of
 * duty per period */
#define BOARD_PWM_ARR_AT(f_pwm) (BOARD_SYSCLK_HZ / (2u * (f_pwm)))

#endif
