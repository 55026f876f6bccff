/*
 * board.h - selects the board header from the FD_BOARD_* macro that
 * hal/stm32g4/CMakeLists.txt defines from the FD_BOARD cache variable.
 */
#ifndef FLUXDRIVE_STM32G4_BOARD_H
#define FLUXDRIVE_STM32G4_BOARD_H

#include "gpio.h"
#include "stm32g4_regs.h"

#if defined(FD_BOARD_G474)
#include "boards/board_g474_nucleo.h"
#elif defined(FD_BOARD_B_G431B_ESC1)
#include "boards/board_b_g431b_esc1.h"
#else
#error "define FD_BOARD_G474 or FD_BOARD_B_G431B_ESC1 (FD_BOARD cache variable)"
#endif

/* The PWM (and ISR) frequency of the build: the board's, or the CMake cache
 * variable FD_PWM_HZ (e.g. 32000 for the deadbeat law's shorter period,
 * preset stm32g474-32k; issue 24). The drive's period follows
 * (boards/stm32g4/board_main.c: ts from BOARD_PWM_ARR). */
#if defined(FD_PWM_HZ)
#undef BOARD_PWM_HZ
#define BOARD_PWM_HZ FD_PWM_HZ
#endif

#include "board_clock.h"

/* TIM1 centre-aligned: f_pwm = f_tim / (2 ARR) */
#define BOARD_PWM_ARR BOARD_PWM_ARR_AT(BOARD_PWM_HZ)

#endif
