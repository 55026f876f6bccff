/*
 * gpio.h - pin description used by the board headers and the small GPIO
 * helpers (RM0440 section 9: MODER, OTYPER, OSPEEDR, PUPDR, AFRL/AFRH).
 */
#ifndef FLUXDRIVE_STM32G4_GPIO_H
#define FLUXDRIVE_STM32G4_GPIO_H

#include <stdint.h>

enum { PORT_A = 0, PORT_B = 1, PORT_C = 2, PORT_D = 3, PORT_E = 4, PORT_F = 5, PORT_G = 6 };

typedef struct {
  uint8_t port; /* PORT_A.. */
  uint8_t pin;  /* 0..15 */
  uint8_t af;   /* alternate function number 0..15 */
} hal_pin_t;

/* Clock the port and put the pin in alternate function mode, push-pull,
 * very high speed, with the given pull (0 none, 1 up, 2 down). */
void hal_gpio_af(hal_pin_t p, uint32_t pull);
/* Analog mode (ADC / OPAMP inputs). */
void hal_gpio_analog(uint8_t port, uint8_t pin);

#endif
