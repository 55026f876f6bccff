/*
 * clock.c - 170 MHz system clock, RM0440 section 6.1.5 (dynamic voltage
 * scaling: range 1 boost mode), 3.3.3 (flash read access latency) and 7.2
 * (clocks: PLL, system clock switch, AHB prescaler sequence).
 *
 * PLL: f_in / M = 4 MHz (input range 2.66..16 MHz), x N = 85 -> VCO 340 MHz
 * (96..344 MHz), / R = 2 -> 170 MHz.
 */
#include "clock.h"

#include "board.h"

#define PLL_IN_HZ     4000000u
#define PLL_N         85u
#define READY_TIMEOUT 200000u

_Static_assert(BOARD_HSE_HZ == 0u || BOARD_HSE_HZ % PLL_IN_HZ == 0u,
               "HSE must be a multiple of 4 MHz");
_Static_assert((BOARD_HSE_HZ == 0u ? 16000000u : BOARD_HSE_HZ) / PLL_IN_HZ <= 16u, "PLLM range");

void hal_delay_cycles(uint32_t n) {
  /* about 3 cycles per iteration; volatile keeps the loop */
  for (volatile uint32_t i = 0; i < n / 3u + 1u; i++) {
  }
}

static int wait_set(const reg32_t *reg, uint32_t mask) {
  for (uint32_t t = 0; t < READY_TIMEOUT; t++) {
    if ((*reg & mask) != 0u) {
      return 0;
    }
  }
  return -1;
}

int hal_clock_init(void) {
  const uint32_t f_src = (BOARD_HSE_HZ != 0u) ? BOARD_HSE_HZ : 16000000u;
  const uint32_t pllm = f_src / PLL_IN_HZ;

  RCC->APB1ENR1 |= RCC_APB1ENR1_PWREN;
  (void)RCC->APB1ENR1;

  /* 1. Flash: 4 wait states for 136..170 MHz in range 1 boost (RM0440
   * table "Number of wait states according to CPU clock frequency"),
   * prefetch and caches on; read back until the latency is taken. */
  FLASH->ACR = (FLASH->ACR & ~FLASH_ACR_LATENCY_Msk) | 4u | FLASH_ACR_PRFTEN | FLASH_ACR_ICEN |
               FLASH_ACR_DCEN;
  if (wait_set(&FLASH->ACR, 4u) != 0) {
    return -1;
  }

  /* 2. Range 1 boost mode: R1MODE = 0 (VOS stays at range 1 from reset). */
  PWR->CR5 &= ~PWR_CR5_R1MODE;
  for (uint32_t t = 0; t < READY_TIMEOUT && (PWR->SR2 & PWR_SR2_VOSF) != 0u; t++) {
  }

  /* 3. Oscillator. */
  uint32_t src = RCC_PLLCFGR_SRC_HSI;
  if (BOARD_HSE_HZ != 0u) {
    RCC->CR |= RCC_CR_HSEON;
    if (wait_set(&RCC->CR, RCC_CR_HSERDY) != 0) {
      return -1;
    }
    src = RCC_PLLCFGR_SRC_HSE;
  }

  /* 4. PLL (configured while off), R output enabled. */
  RCC->CR &= ~RCC_CR_PLLON;
  for (uint32_t t = 0; t < READY_TIMEOUT && (RCC->CR & RCC_CR_PLLRDY) != 0u; t++) {
  }
  RCC->PLLCFGR =
      src | ((pllm - 1u) << RCC_PLLCFGR_M_Pos) | (PLL_N << RCC_PLLCFGR_N_Pos); /* PLLR = 00: /2 */
  RCC->CR |= RCC_CR_PLLON;
  if (wait_set(&RCC->CR, RCC_CR_PLLRDY) != 0) {
    return -1;
  }
  RCC->PLLCFGR |= RCC_PLLCFGR_PLLREN;

  /* 5. Boost-mode switch sequence: AHB /2 first, switch SYSCLK to the PLL,
   * wait >= 1 us, then AHB /1. APB1 = APB2 = HCLK. */
  RCC->CFGR = (RCC->CFGR & ~(RCC_CFGR_HPRE_Msk | RCC_CFGR_PPRE1_Msk | RCC_CFGR_PPRE2_Msk)) |
              (RCC_CFGR_HPRE_DIV2 << RCC_CFGR_HPRE_Pos);
  RCC->CFGR = (RCC->CFGR & ~RCC_CFGR_SW_Msk) | RCC_CFGR_SW_PLL;
  for (uint32_t t = 0; t < READY_TIMEOUT; t++) {
    if (((RCC->CFGR & RCC_CFGR_SWS_Msk) >> RCC_CFGR_SWS_Pos) == RCC_CFGR_SW_PLL) {
      break;
    }
  }
  hal_delay_cycles(400u);          /* >= 1 us at 85 MHz */
  RCC->CFGR &= ~RCC_CFGR_HPRE_Msk; /* HPRE = 0000: /1 */
  return (((RCC->CFGR & RCC_CFGR_SWS_Msk) >> RCC_CFGR_SWS_Pos) == RCC_CFGR_SW_PLL) ? 0 : -1;
}
