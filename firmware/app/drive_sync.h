/*
 * drive_sync.h - the ordering primitive of the ISR / main-loop contract
 * (drive.h): drive.c (the ISR's side) and drive_host.c (the main loop's).
 */
#ifndef FLUXDRIVE_DRIVE_SYNC_H
#define FLUXDRIVE_DRIVE_SYNC_H

#include <stdatomic.h>

/* Orders the accesses of one context around a shared word. The ISR and the
 * main loop run on one core (the ISR preempts, is never preempted by the
 * main loop): a compiler barrier is all the ordering they need. */
#define DRIVE_BARRIER() atomic_signal_fence(memory_order_seq_cst)

#endif
