/*
 * board_g474_nucleo.c - the NUCLEO-G474RE board as the SIL models it: the
 * numbers of its board header (hal/stm32g4/boards/board_g474_nucleo.h).
 */
#include "board_presets.h"

#include "board_clock.h"
#include "boards/board_g474_nucleo.h"

const sil_board_preset_t sil_board_g474_nucleo = {"g474_nucleo", BOARD_SYSCLK_HZ, 0.0f,
                                                  BOARD_DUTY_MAX, BOARD_IWDG_TIMEOUT_MS};
