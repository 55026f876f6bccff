/*
 * board_b_g431b_esc1.c - the B-G431B-ESC1 board as the SIL models it: the
 * numbers of its board header (hal/stm32g4/boards/board_b_g431b_esc1.h).
 */
#include "board_presets.h"

#include "board_clock.h"
#include "boards/board_b_g431b_esc1.h"

const sil_board_preset_t sil_board_b_g431b_esc1 = {"b_g431b_esc1", BOARD_SYSCLK_HZ, 0.0f,
                                                   BOARD_DUTY_MAX, BOARD_IWDG_TIMEOUT_MS};
