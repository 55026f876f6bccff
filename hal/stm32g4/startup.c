/*
 * startup.c - vector table and reset handler for STM32G4 (Cortex-M4F).
 *
 * Reset sequence: (1) FPU access enabled (CPACR CP10/CP11, PM0214 4.6.1)
 * before any code that may use a floating-point register, (2) .data copied
 * and .bss zeroed, then the CCM SRAM code/data (.ccmram) copied and .ccmbss
 * zeroed, (3) VTOR, (4) clock tree (clock.c), (5) main().
 *
 * Every unused interrupt and every fault goes to a handler that turns the
 * gates off (TIM1 BDTR.MOE = 0: outputs to their idle level, all switches
 * off) and stays there; the watchdog (if started) then resets the MCU.
 */
#include <stdint.h>

#include "clock.h"
#include "stm32g4_regs.h"

/* Linker script symbols (stm32g4_common.ld). */
extern uint32_t _estack;
extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss;
extern uint32_t _siccmram, _sccmram, _eccmram, _sccmbss, _eccmbss;

int main(void);
void Reset_Handler(void);
void fd_startup(void);
void Default_Handler(void);
void HardFault_Handler(void);
void NMI_Handler(void) __attribute__((weak, alias("Default_Handler")));
void MemManage_Handler(void) __attribute__((weak, alias("HardFault_Handler")));
void BusFault_Handler(void) __attribute__((weak, alias("HardFault_Handler")));
void UsageFault_Handler(void) __attribute__((weak, alias("HardFault_Handler")));
void SVC_Handler(void) __attribute__((weak, alias("Default_Handler")));
void DebugMon_Handler(void) __attribute__((weak, alias("Default_Handler")));
void PendSV_Handler(void) __attribute__((weak, alias("Default_Handler")));
void SysTick_Handler(void) __attribute__((weak, alias("Default_Handler")));
void ADC1_2_IRQHandler(void) __attribute__((weak, alias("Default_Handler")));
void TIM1_BRK_TIM15_IRQHandler(void) __attribute__((weak, alias("Default_Handler")));

typedef void (*vector_t)(void);

#define CORE_VECTORS 16u

/* RM0440 section 16.3: 16 core exceptions followed by 102 peripheral
 * interrupts (STM32G474; the G431 leaves some of them reserved). Position
 * 18 is ADC1_2, 24 is TIM1_BRK_TIM15. */
#define D Default_Handler
__attribute__((section(".isr_vector"), used))
const vector_t g_vectors[CORE_VECTORS + STM32G4_IRQ_COUNT] = {
    (vector_t)(uintptr_t)&_estack,
    Reset_Handler,
    NMI_Handler,
    HardFault_Handler,
    MemManage_Handler,
    BusFault_Handler,
    UsageFault_Handler,
    0,
    0,
    0,
    0,
    SVC_Handler,
    DebugMon_Handler,
    0,
    PendSV_Handler,
    SysTick_Handler,
    /*   0 */ D,
    D,
    D,
    D,
    D,
    D,
    /*   6 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  12 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  18 */ ADC1_2_IRQHandler,
    D,
    D,
    D,
    D,
    D,
    /*  24 */ TIM1_BRK_TIM15_IRQHandler,
    D,
    D,
    D,
    D,
    D,
    /*  30 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  36 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  42 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  48 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  54 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  60 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  66 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  72 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  78 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  84 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  90 */ D,
    D,
    D,
    D,
    D,
    D,
    /*  96 */ D,
    D,
    D,
    D,
    D,
    D,
};
#undef D
_Static_assert(IRQN_ADC1_2 == 18u && IRQN_TIM1_BRK_TIM15 == 24u, "vector positions above");

/* First instructions after reset: no C code (the compiler may use FPU
 * registers) before CP10/CP11 are enabled. */
__attribute__((naked, noreturn)) void Reset_Handler(void) {
  __asm__ volatile("movw r0, #0xED88\n\t"
                   "movt r0, #0xE000\n\t" /* SCB->CPACR */
                   "ldr r1, [r0]\n\t"
                   "orr r1, r1, #0x00F00000\n\t"
                   "str r1, [r0]\n\t"
                   "dsb\n\t"
                   "isb\n\t"
                   "b fd_startup\n");
}

static void copy_words(uint32_t *dst, const uint32_t *src, const uint32_t *end) {
  while (dst < end) {
    *dst++ = *src++;
  }
}

static void zero_words(uint32_t *dst, const uint32_t *end) {
  while (dst < end) {
    *dst++ = 0u;
  }
}

__attribute__((used, noreturn, optimize("no-tree-loop-distribute-patterns"))) void
fd_startup(void) {
  copy_words(&_sdata, &_sidata, &_edata);
  zero_words(&_sbss, &_ebss);
  copy_words(&_sccmram, &_siccmram, &_eccmram);
  zero_words(&_sccmbss, &_eccmbss);
  SCB->VTOR = (uint32_t)(uintptr_t)g_vectors;
  __asm__ volatile("dsb\n\tisb" ::: "memory");
  (void)hal_clock_init(); /* on failure SYSCLK stays HSI16; hal_pwm init checks it */
  (void)main();
  for (;;) {
    Default_Handler();
  }
}

static void gates_off(void) {
  TIM1->BDTR &= ~TIM_BDTR_MOE;
}

void Default_Handler(void) {
  gates_off();
  for (;;) {
  }
}

void HardFault_Handler(void) {
  gates_off();
  for (;;) {
  }
}
