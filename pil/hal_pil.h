/*
 * hal_pil.h - hal.h for the PIL image: the ADC sample, the hardware trip
 * input and the time come from a recorded isr_stream input record; duties
 * and the gate state are kept for the output record. Clamping and the gate
 * rules are those of hal/sil (the host build it is compared with).
 */
#ifndef FD_PIL_HAL_PIL_H
#define FD_PIL_HAL_PIL_H

#include <stdbool.h>

#include "isr_stream.h"

/* Sets what the next drive_isr() reads. */
void hal_pil_set_input(const isr_stream_in_t *in);
/* Duties and gate state after the ISR. */
void hal_pil_get_output(float duty[3], bool *gates_on);

#endif
