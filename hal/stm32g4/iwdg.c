/*
 * iwdg.c - independent watchdog, RM0440 section 41.3 (configuration
 * sequence: enable 0xCCCC, unlock 0x5555, PR and RLR, wait SR = 0, reload
 * 0xAAAA). Clock: LSI 32 kHz; prescaler /32 -> 1 ms per count, RLR <= 4095.
 * Frozen while the core is halted by a debugger (DBGMCU_APB1FZR1).
 */
#include "iwdg.h"

#include "hal.h"
#include "stm32g4_regs.h"

void hal_watchdog_start(uint32_t timeout_ms) {
  uint32_t rl = timeout_ms;
  if (rl < 1u) {
    rl = 1u;
  }
  if (rl > 4095u) {
    rl = 4095u;
  }
  DBGMCU->APB1FZR1 |= DBGMCU_APB1FZR1_IWDG_STOP;
  IWDG->KR = IWDG_KEY_ENABLE; /* starts the LSI */
  IWDG->KR = IWDG_KEY_ACCESS;
  IWDG->PR = 3u; /* /32 */
  IWDG->RLR = rl - 1u;
  for (uint32_t t = 0; t < 1000000u && IWDG->SR != 0u; t++) {
  }
  IWDG->KR = IWDG_KEY_RELOAD;
}

void hal_watchdog_kick(void) {
  IWDG->KR = IWDG_KEY_RELOAD;
}

/* RCC_CSR (RM0440 7.4.29): IWDGRSTF bit 29, cleared with RMVF bit 23.
 * Read once, at the first call (before anything clears it). */
bool hal_reset_by_watchdog(void) {
  static int cause = -1;
  if (cause < 0) {
    cause = (RCC->CSR & (1u << 29)) != 0u ? 1 : 0;
    RCC->CSR |= 1u << 23; /* RMVF: the next reset reports its own cause */
  }
  return cause != 0;
}
