/*
 * board_presets.c - lookup of the SIL's board presets (board_presets.h).
 */
#include "board_presets.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

static const sil_board_preset_t ideal = {"ideal", 0u, 0.0f, 1.0f, 0u};

static const sil_board_preset_t *const boards[] = {&sil_board_g474_nucleo, &sil_board_b_g431b_esc1,
                                                   &ideal};

const sil_board_preset_t *sil_board_find(const char *name) {
  for (size_t i = 0; name != NULL && i < sizeof boards / sizeof boards[0]; ++i) {
    if (strcmp(boards[i]->name, name) == 0) {
      return boards[i];
    }
  }
  return NULL;
}

const char *sil_board_names(void) {
  return "g474_nucleo, b_g431b_esc1, ideal";
}

void sil_board_apply(const sil_board_preset_t *p, double ts, double dead_time, hal_sil_board_t *b) {
  b->duty_min = p->duty_min;
  b->duty_max = p->duty_max;
  b->timer_counts = p->timer_hz > 0u ? (uint32_t)floor(0.5 * p->timer_hz * ts) : 0u;
  b->dead_time = (float)dead_time;
  b->ts = (float)ts;
  b->watchdog_ms = p->watchdog_ms;
  b->asym_edges = false;
}
