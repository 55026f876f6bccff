/*
 * sil_preempt.h - the SIL with the ISR preempting the main loop at random
 * points, to find races between the two contexts of the drive (drive.h,
 * "Concurrency contract").
 *
 * On the MCU the PWM-period interrupt preempts the main loop between any
 * two instructions. Here a second thread sends SIGUSR1 to the main thread
 * after random gaps (busy-waited, microseconds); the signal handler runs
 * one PWM period on top of whatever the main thread was doing: sample the
 * plant, drive_isr(), check the drive's invariants, advance the plant. The
 * main thread meanwhile runs the drive's main-loop side as fast as it can,
 * driven by a seeded random sequence: commands (enable, disable, torque,
 * speed, mode, law), fault clears and fault requests, parameter writes
 * (LIVE and IDLE), telemetry copies (checked for consistency) and the
 * background service. Nothing in either context takes a lock: the
 * protocols of drive.h are what is tested.
 *
 * Invariants checked after every ISR (in the handler, where the drive is
 * not changing):
 *  - a drive in idle, offset calibration, alignment or run has no fault
 *    latched; a drive in fault has one, and its gates are off;
 *  - the gates are on only in run or alignment;
 *  - the parameter set in force passes drive_config_check, and the ISR
 *    never refuses a set the main loop validated (never a mix of two
 *    requested sets);
 *  - when the main loop was not half-way through a command block, the
 *    ISR's copy equals the block (nothing lost); when it was, the ISR kept
 *    the block it had (nothing torn);
 *  - a fault request taken by this ISR (not voided by a clear) is latched;
 *  - idle -> offset calibration happens only with enable commanded, and
 *    never before the enable that follows a clear.
 * And in the main loop, every telemetry copy that drive_telemetry_read()
 * reports consistent has isr_count == isr_count_end. After the run, with
 * the handler stopped: every fault request was taken.
 */
#ifndef FD_SIL_PREEMPT_H
#define FD_SIL_PREEMPT_H

#include <stddef.h>
#include <stdint.h>

#include "scenario.h"

typedef struct {
  uint64_t periods;  /* how many ISRs to run */
  double wall_max_s; /* ... or stop after this much wall time [s] */
  uint32_t seed;     /* the main loop's random sequence */
  double max_gap_us; /* preemption gaps uniform in [0, max_gap_us] */
} sil_preempt_opts_t;

typedef struct {
  uint64_t periods;         /* ISRs run (in the handler) */
  uint64_t main_iterations; /* main-loop passes */
  uint64_t commands, clears, fault_requests, param_writes, param_refused;
  uint64_t tm_reads, tm_retries, tm_failed;
  uint64_t tm_torn;            /* copies reported consistent that were not (main loop) */
  uint64_t in_publication;     /* ISRs that found the command block half-written */
  uint64_t cfg_in_publication; /* ... the parameter request half-written */
  uint64_t starts, trips;      /* idle -> offset calibration, -> fault */
  uint64_t violations;
  char first_violation[256];
  double wall_s; /* wall time taken [s] */
} sil_preempt_result_t;

/* Runs scenario sc's plant and drive under random preemption. 0 when it
 * ran (violations are results), -1 with a message in err. */
int sil_preempt_run(const scenario_t *sc, const sil_preempt_opts_t *opts, sil_preempt_result_t *r,
                    char *err, size_t errlen);

#endif
