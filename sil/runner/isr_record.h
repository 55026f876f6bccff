/*
 * isr_record.h - records, per ISR, the drive's inputs (HAL sample set, the
 * break input, the main loop's command block as the ISR finds it) and its
 * outputs (pattern duties, gate state, faults, state) into an isr_stream
 * file (isr_stream.h, docs/pil.md), for the processor-in-the-loop replay on
 * QEMU (pil/, `fluxdrive pil`).
 *
 * It is a sil_run observer; it can chain to another observer (the log).
 * The outputs of ISR k are completed at period k+1 (the pattern the HAL
 * holds after ISR k acts over [t_k+1, t_k+2)), so the last ISR of a run is
 * not recorded. Runs with parameter requests (CAN parameter writes) or
 * watchdog resets are not recordable (the recorder stops with an error).
 */
#ifndef FD_SIL_ISR_RECORD_H
#define FD_SIL_ISR_RECORD_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "isr_stream.h"
#include "sil_run.h"

typedef struct {
  FILE *f;
  uint32_t count;
  uint32_t map_bytes; /* the flux map's blob in the configuration section */
  int failed;
  bool started; /* header, config and caps written */
  bool pending; /* rec holds ISR k-1, waiting for its duties */
  isr_stream_in_t in;
  isr_stream_out_t out;
  float prev_v_applied[2]; /* drive_t.v_applied after the last ISR */
  uint32_t isr_count;      /* drive_t.isr_count after the last ISR */
  sil_observer_fn next;    /* chained observer (may be NULL) */
  void *next_user;
} isr_record_t;

/* Opens the file. Returns 0 or -1. */
int isr_record_open(isr_record_t *r, const char *path);
/* sil_run observer. */
void isr_record_observer(void *user, const sil_step_t *st);
/* Patches the record count into the header and closes. Returns 0 or -1. */
int isr_record_close(isr_record_t *r);

#endif
