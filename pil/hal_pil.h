/*
 * hal_pil.h - hal.h for the PIL image: the board's capabilities come from
 * the recorded stream; the sample set, the break input and the time from
 * each input record; the pattern and the gate state are kept for the
 * output record. The timer model (duty limits, rounding) is hal/sil's
 * (hal/hal_pattern.h), the host build it is compared with.
 */
#ifndef FD_PIL_HAL_PIL_H
#define FD_PIL_HAL_PIL_H

#include <stdbool.h>
#include <stdint.h>

#include "isr_stream.h"

/* The recorded board (before drive_init). */
void hal_pil_set_caps(const hal_caps_t *caps, uint32_t timer_counts);
/* Sets what the next drive_isr() reads. */
void hal_pil_set_input(const isr_stream_in_t *in);
/* Duties (off - on) and gate state after the ISR. */
void hal_pil_get_output(float duty[3], bool *gates_on);

#endif
