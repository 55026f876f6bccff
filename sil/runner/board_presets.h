/*
 * board_presets.h - the boards the SIL can model (scenario "board"
 * section, docs/scenarios.md): each preset's numbers come from that
 * board's header in hal/stm32g4/boards/, so the SIL applies the same duty
 * limits, timer resolution and watchdog as the firmware image.
 */
#ifndef FD_SIL_BOARD_PRESETS_H
#define FD_SIL_BOARD_PRESETS_H

#include <stdint.h>

#include "hal_sil.h"

typedef struct {
  const char *name;
  uint32_t timer_hz;        /* PWM timer clock: compare steps = timer_hz / (2 f_pwm); 0: exact */
  float duty_min, duty_max; /* usable duty range */
  uint32_t watchdog_ms;     /* 0: none */
} sil_board_preset_t;

extern const sil_board_preset_t sil_board_g474_nucleo;
extern const sil_board_preset_t sil_board_b_g431b_esc1;

/* NULL when unknown; "ideal" is an exact timer over [0, 1], no watchdog. */
const sil_board_preset_t *sil_board_find(const char *name);
/* Comma-separated names, for error messages. */
const char *sil_board_names(void);
/* The board the SIL models for a preset at PWM period ts. */
void sil_board_apply(const sil_board_preset_t *p, double ts, double dead_time, hal_sil_board_t *b);

#endif
