/*
 * board_main.c - main() of the STM32G4 firmware: drive configuration from
 * the board header, peripheral bring-up, the PWM-period interrupt body and
 * the 1 kHz main loop (SysTick tick, thread mode: CAN, background service).
 */
#include <stdint.h>

#include "board.h"
#include "can_proto.h"
#include "drive.h"
#include "hal.h"
#include "hal_stm32g4.h"

/* The drive instance (globals are allowed outside firmware/core). Placed in
 * CCM SRAM: the ISR's data on the zero-wait-state D-bus. */
static drive_t s_drv __attribute__((section(".ccmbss.drive")));
static can_proto_t s_can;
static volatile uint32_t s_ticks;

/* Readable with a debugger: HAL_INIT_ERR_* bits, and the drive_init field. */
volatile uint32_t g_board_init_error;
const char *volatile g_board_config_field;

void SysTick_Handler(void);

void SysTick_Handler(void) {
  s_ticks++;
}

/* Called by ADC1_2_IRQHandler at the end of the injected sequence. */
__attribute__((section(".ccmram.text.board"))) void board_control_isr(void) {
  drive_isr(&s_drv);
}

static void systick_start_1khz(void) {
  /* PM0214 4.5: processor clock, reload 170000 - 1 -> 1 ms; priority below
   * the ADC interrupt (SHPR3 byte of exception 15). */
  SYSTICK->LOAD = BOARD_SYSCLK_HZ / 1000u - 1u;
  SYSTICK->VAL = 0u;
  SCB->SHPR[15u - 4u] = (uint8_t)(8u << (8u - NVIC_PRIO_BITS));
  SYSTICK->CTRL = SYSTICK_CTRL_CLKSOURCE | SYSTICK_CTRL_TICKINT | SYSTICK_CTRL_ENABLE;
}

static void board_config(drive_config_t *cfg) {
  drive_config_default(cfg);
  cfg->enc_cpr = 0u; /* no encoder input on these boards: the position fault refuses to run */
  cfg->ts = (float)(2u * BOARD_PWM_ARR) / (float)BOARD_SYSCLK_HZ;
  cfg->slow_div = (uint16_t)(BOARD_PWM_HZ / 1000u);
  cfg->dead_time = (float)BOARD_DEAD_TIME_NS * 1.0e-9f;
  cfg->i_trip = BOARD_I_TRIP;
  cfg->v_dc_max = BOARD_V_DC_MAX;
  cfg->v_dc_min = BOARD_V_DC_MIN;
}

__attribute__((noreturn)) static void halt_gates_off(void) {
  hal_pwm_disable();
  for (;;) {
    __asm__ volatile("wfi");
  }
}

int main(void) {
  drive_config_t cfg;
  board_config(&cfg);

  uint32_t err = hal_stm32g4_init(); /* gates off */
  (void)hal_reset_by_watchdog();     /* latch the reset cause before anything */
  drive_config_err_t cerr;
  if (drive_init(&s_drv, &cfg, &cerr) != 0) {
    g_board_config_field = cerr.field;
    err |= 0x80000000u;
  }
  can_proto_cfg_t can_cfg;
  can_proto_cfg_default(&can_cfg);
  can_cfg.node = (uint8_t)BOARD_CAN_NODE_ID;
  if (can_proto_init(&s_can, &can_cfg) != 0) {
    err |= 0x40000000u;
  }
  if (err == 0u) {
    err |= hal_stm32g4_start(); /* PWM carrier + ADC trigger + ISR */
  }
  g_board_init_error = err;
  if (err != 0u) {
    halt_gates_off();
  }

  systick_start_1khz();
  hal_watchdog_start(BOARD_IWDG_TIMEOUT_MS);

  uint32_t done = s_ticks;
  for (;;) {
    const uint32_t now = s_ticks;
    if (now != done) {
      /* one main-loop pass per tick; after a long stall, skip the missed ones */
      done = (now - done > 4u) ? now : done + 1u;
      /* telemetry copy, and the watchdog refresh: only here, and only when
       * the PWM-period interrupt advanced since the last one (drive.h) */
      drive_background(&s_drv);
      /* CAN commands are posted here and taken by the next ISR */
      can_proto_poll(&s_can, &s_drv, hal_time_us());
    } else {
      __asm__ volatile("wfi");
    }
  }
}
