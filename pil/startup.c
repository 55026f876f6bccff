/*
 * startup.c - reset and fault handlers of the PIL image (QEMU mps2-an386).
 * The FPU is enabled (CPACR CP10/CP11 full access) before any code that
 * may use it, then .data is copied and .bss cleared, then main() runs.
 * A fault ends the emulation with exit status 70.
 */
#include <stdint.h>

#include "semihost.h"

extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
int main(void);
void Reset_Handler(void);
void Fault_Handler(void);

#define SCB_CPACR (*(volatile uint32_t *)0xE000ED88u)

__attribute__((noreturn)) void Reset_Handler(void) {
  SCB_CPACR |= (0xFu << 20); /* CP10, CP11: full access */
  __asm__ volatile("dsb\n\tisb" ::: "memory");
  const uint32_t *src = &_sidata;
  /* linker symbols bound one region each: comparing them is the point */
  // cppcheck-suppress comparePointers
  for (uint32_t *dst = &_sdata; dst < &_edata;) {
    *dst++ = *src++;
  }
  // cppcheck-suppress comparePointers
  for (uint32_t *dst = &_sbss; dst < &_ebss;) {
    *dst++ = 0u;
  }
  sh_exit((uint32_t)main());
}

__attribute__((noreturn)) void Fault_Handler(void) {
  sh_puts("fluxdrive-pil: fault exception\n");
  sh_exit(70u);
}

/* Initial SP, reset, NMI, HardFault, MemManage, BusFault, UsageFault. */
__attribute__((section(".isr_vector"), used)) static void (*const vectors[])(void) = {
    (void (*)(void))(uintptr_t)&_estack,
    Reset_Handler,
    Fault_Handler,
    Fault_Handler,
    Fault_Handler,
    Fault_Handler,
    Fault_Handler,
};
