/* hal_time.h - microsecond time base (TIM2, RM0440 section 29) and the
 * core cycle counter (DWT) used for ISR profiling. */
#ifndef FLUXDRIVE_STM32G4_HAL_TIME_H
#define FLUXDRIVE_STM32G4_HAL_TIME_H

/* TIM2: 32-bit up-counter at 1 MHz (PSC = 169 at 170 MHz), wraps after
 * 2^32 us as hal.h specifies. Also starts DWT->CYCCNT. */
void hal_time_init(void);

#endif
