/*
 * time.c - hal_time_us from TIM2 (RM0440 section 29: 32-bit general-purpose
 * timer) clocked at 170 MHz, PSC = 169 -> 1 MHz, ARR = 0xFFFFFFFF, so the
 * counter itself is the free-running microsecond time. The DWT cycle counter
 * (ARMv7-M ARM C1.8.8) is started for the ISR cycle measurement.
 */
#include "board.h"
#include "hal.h"
#include "hal_time.h"

void hal_time_init(void) {
  RCC->APB1ENR1 |= RCC_APB1ENR1_TIM2EN;
  (void)RCC->APB1ENR1;
  DBGMCU->APB1FZR1 |= DBGMCU_APB1FZR1_TIM2_STOP;
  TIM2->CR1 = 0u;
  TIM2->PSC = BOARD_SYSCLK_HZ / 1000000u - 1u;
  TIM2->ARR = 0xFFFFFFFFu;
  TIM2->CNT = 0u;
  TIM2->EGR = TIM_EGR_UG; /* load PSC */
  TIM2->SR = 0u;
  TIM2->CR1 = TIM_CR1_CEN;

  DEMCR |= DEMCR_TRCENA;
  DWT->CYCCNT = 0u;
  DWT->CTRL |= DWT_CTRL_CYCCNTENA;
}

uint32_t hal_time_us(void) {
  return TIM2->CNT;
}
