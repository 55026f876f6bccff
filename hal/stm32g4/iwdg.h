/* iwdg.h - independent watchdog (RM0440 section 41). hal_watchdog_start is
 * declared in hal_stm32g4.h, hal_watchdog_kick in hal.h. */
#ifndef FLUXDRIVE_STM32G4_IWDG_H
#define FLUXDRIVE_STM32G4_IWDG_H
#include "hal_stm32g4.h"
#endif
