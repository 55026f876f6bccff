/*
 * hal_stm32g4.c - bring-up of the STM32G4 HAL and where each hal.h function
 * lives:
 *   hal_adc_read                      adc.c (JDR of ADC1/ADC2 -> SI)
 *   hal_pwm_set_duty/enable/disable/is_enabled,
 *   hal_fault_hw_tripped/source/clear pwm_tim1.c (CCRx, BDTR.MOE, SR.BIF, B2IF)
 *   hal_can_send/receive              fdcan.c (Tx FIFO, Rx FIFO 0)
 *   hal_time_us                       time.c (TIM2 at 1 MHz)
 *   hal_watchdog_kick                 iwdg.c
 * Each is implemented next to its registers so the ISR path has no extra
 * call layer.
 */
#include "hal_stm32g4.h"

#include "adc.h"
#include "board.h"
#include "break_comp.h"
#include "cordic.h"
#include "fdcan.h"
#include "hal.h"
#include "hal_time.h"
#include "pwm_tim1.h"

uint32_t hal_stm32g4_init(void) {
  uint32_t err = 0u;
  if (((RCC->CFGR & RCC_CFGR_SWS_Msk) >> RCC_CFGR_SWS_Pos) != RCC_CFGR_SW_PLL) {
    err |= HAL_INIT_ERR_CLOCK; /* every timing below assumes 170 MHz */
  }
  hal_time_init();
  hal_cordic_init();
  hal_tim1_init(); /* gates off from here on */
  if (!hal_adc_init()) {
    err |= HAL_INIT_ERR_ADC;
  }
  if (!hal_break_comp_init()) { /* after the op-amps and analog pins */
    err |= HAL_INIT_ERR_BREAK;
  }
  /* The protocol's identifiers are base + node with the node in the low
   * nibble (firmware/app/can/fluxdrive.dbc): accept every base for this
   * node; can_proto ignores the bases it does not handle. */
  if (!hal_fdcan_init(BOARD_CAN_BITRATE, BOARD_CAN_NODE_ID, 0x00Fu)) {
    err |= HAL_INIT_ERR_CAN;
  }
  /* The break inputs have settled (the BKIN pin and its pull-up since
   * hal_tim1_init, the comparators since hal_break_comp_init): a break
   * flagged while they came up is cleared; one still active stays set and
   * is the drive's hw_overcurrent from its first ISR. */
  hal_fault_hw_clear();
  return err;
}

uint32_t hal_stm32g4_start(hal_control_fn control) {
  const uint32_t pm = hal_irq_save();
  const bool aligned = hal_tim1_start();
  const bool armed = hal_adc_start(control);
  hal_irq_restore(pm);
  return (aligned ? 0u : HAL_INIT_ERR_PWM) | (armed ? 0u : HAL_INIT_ERR_ISR);
}
