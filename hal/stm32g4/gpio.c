/* gpio.c - GPIO configuration, RM0440 section 9.4. */
#include "gpio.h"

#include "stm32g4_regs.h"

static void gpio_clock(uint8_t port) {
  RCC->AHB2ENR |= RCC_AHB2ENR_GPIOAEN << port;
  (void)RCC->AHB2ENR; /* read back: the clock is running before the access */
}

void hal_gpio_af(hal_pin_t p, uint32_t pull) {
  gpio_clock(p.port);
  gpio_regs_t *g = GPIO_BASE(p.port);
  const uint32_t s2 = 2u * p.pin;
  const uint32_t s4 = 4u * (p.pin & 7u);
  g->AFR[p.pin >> 3] = (g->AFR[p.pin >> 3] & ~(0xFu << s4)) | ((uint32_t)p.af << s4);
  g->OTYPER &= ~(1u << p.pin);
  g->OSPEEDR |= 3u << s2;
  g->PUPDR = (g->PUPDR & ~(3u << s2)) | ((pull & 3u) << s2);
  g->MODER = (g->MODER & ~(3u << s2)) | (GPIO_MODE_AF << s2);
}

void hal_gpio_analog(uint8_t port, uint8_t pin) {
  gpio_clock(port);
  gpio_regs_t *g = GPIO_BASE(port);
  const uint32_t s2 = 2u * pin;
  g->PUPDR &= ~(3u << s2);
  g->MODER |= GPIO_MODE_ANALOG << s2;
}
