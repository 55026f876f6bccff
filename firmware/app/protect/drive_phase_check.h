/*
 * protect/drive_phase_check.h - phase balance, checked by the main loop
 * on the telemetry copy (no ISR cost). An owned part of the drive's
 * protections (docs/architecture.md, "Adding a protection"): its state in
 * drive_t.host (main-loop owned), a step on a read-only view of the
 * telemetry copy that returns the fault the main loop requests. The file
 * keeps its name because the G474 linker script lists it among the files
 * kept out of the CCM (hal/stm32g4/stm32g474re.ld).
 *
 * Over one electrical revolution every phase carries the same mean |i_x|.
 * An open phase (a motor lead off) or a lost one (both switches of a leg
 * off) carries none; the ISR's current-sum check does not see it (the
 * currents still sum to zero). Each fresh telemetry copy with the drive in
 * RUN is one sample (its offset-corrected currents); the angle swept comes
 * from the speed estimate and the ISRs between copies. A revolution is
 * judged when it spans at least DRIVE_PH_MIN_N samples (no aliasing of the
 * means: f_e at most a quarter of the main-loop rate, 250 Hz at 1 kHz) and
 * at most DRIVE_PH_MAX_N (slower: nearly DC currents are legitimately
 * unequal) and its largest mean |i_x| exceeds DRIVE_PH_FLOOR i_max. A phase
 * whose mean |i_x| is below DRIVE_PH_OPEN of the largest in DRIVE_PH_TRIP
 * revolutions in a row (one not judged starts the count again; a transient
 * such as a torque step unbalances one) requests lost_control
 * (drive_request_fault: taken by the next ISR) and counts in `trips`.
 *
 * Voltage balance, on the same revolutions: a switch stuck open (or a leg
 * that cannot reach one rail) takes from its phase the voltage the drive
 * believes it applied, in one half-wave only: the drive's own v_ab_applied
 * less R_s i_ab, whose mean over a revolution is the flux change (zero in
 * steady state: v - R i = d lambda / dt), then carries a stationary (DC)
 * component along that phase's axis, the missing voltage. A healthy drive's
 * is the dead-time compensation's asymmetry and R_s errors times a DC
 * current: millivolts. The main loop's samples are not uniform in angle,
 * so the DC part D is fitted by least squares over the revolution's
 * samples together with the rotor-frame voltage turning with the rotor,
 * (F0 + F1 tau) e^{j theta} (the back-EMF, the largest term, and its drift
 * over the revolution: tau the fraction of it swept, so ramps of speed,
 * torque and flux do not leak into D): x_k = D + (F0 + F1 tau_k) e^{j
 * theta_k}. With the real block B = [n, St; St, Stt] of the fundamental's
 * two terms (St = sum tau_k, Stt = sum tau_k^2), c = (S1, St1)
 * (S1 = sum e^{j theta_k}, St1 = sum tau_k e^{j theta_k}) and the right
 * sides r1 = sum x_k, rF = (sum x_k e^{-j theta_k}, sum tau_k x_k e^{-j
 * theta_k}): D = (r1 - c B^-1 rF) / (n - c B^-1 c^H). A revolution with
 * |D| > DRIVE_PH_VDEF v_dc is unbalanced like one with a dead phase (the
 * same count of DRIVE_PH_TRIP in a row, the same request); `vdef_ab` keeps
 * D / v_dc of the last judged revolution (its direction names the phase:
 * a high side stuck open along +x, a low side along -x, x its phase's
 * axis), `vdef` its magnitude, `vdef_max` the largest. A step
 * (torque, flux) still leaks into D for the revolution it falls in: two in
 * a row are needed.
 */
#ifndef FLUXDRIVE_PROTECT_PHASE_CHECK_H
#define FLUXDRIVE_PROTECT_PHASE_CHECK_H

#include <stdbool.h>
#include <stdint.h>

#define DRIVE_PH_MIN_N 4
#define DRIVE_PH_MAX_N 64
#define DRIVE_PH_TRIP  2
/* below 0.08 of the largest: an open or lost phase gives 0.02 at most (the
 * lost leg's diodes), healthy runs 0.14 at least (the decoupled DFVC's
 * stationary current at light load, tests/python/test_fabbri2022_kf.py) */
#define DRIVE_PH_OPEN  0.08f
#define DRIVE_PH_FLOOR 0.05f
/* the missing voltage of a switch stuck open at 300 rpm on the Rubino SPM:
 * 0.045 v_dc at 2 N m, 0.08 at 10 N m; the healthy run 0.0017 in steady
 * state (tests/sil/test_power_faults.c, docs/faults.md) */
#define DRIVE_PH_VDEF 0.02f

/* The sums over one window (one revolution): complex ones [0] real, [1]
 * imaginary; x = v_applied - R_s i in (alpha, beta) [V], tau the
 * revolution's fraction swept. */
typedef struct {
  float abs[3]; /* sum |i_x| [A] */
  float r1[2];  /* sum x */
  float r2[2];  /* sum x e^{-j theta} */
  float r3[2];  /* sum tau x e^{-j theta} */
  float s1[2];  /* sum e^{j theta} */
  float st1[2]; /* sum tau e^{j theta} */
  float st;     /* sum tau */
  float stt;    /* sum tau^2 */
  float angle;  /* electrical angle swept [rad] */
  int32_t n;    /* samples */
} drive_ph_window_t;

typedef struct {
  drive_ph_window_t w; /* the window under way */
  float vdef_ab[2];    /* D / v_dc of the last judged revolution (alpha, beta) */
  float vdef;          /* |D| / v_dc of the last judged revolution */
  float vdef_max;      /* the largest vdef since start-up */
  int32_t bad;         /* unbalanced revolutions in a row */
  uint32_t isr_last;   /* isr_count of the last sample (0: none) */
  uint32_t trips;      /* lost_control requests made */
} drive_phase_check_t;

/* What the check reads: the main loop's telemetry copy and the parameters
 * requested (filled by drive_host.c). */
typedef struct {
  uint32_t isr_count;     /* of the copy (0: none yet) */
  bool run;               /* the copy's state is run */
  float omega_m;          /* [rad/s] */
  const float *i_abc;     /* offset-corrected phase currents [A] */
  const float *v_ab_filt; /* the applied voltage, low-passed (drive.h DRIVE_VF_K) [V] */
  float theta_e;          /* [rad] */
  float v_dc;             /* [V] */
  float pole_pairs, ts, rs, i_max;
} drive_phase_view_t;

/* One main-loop period (drive_background, after the telemetry copy):
 * DRIVE_FAULT_LOST_CONTROL when the main loop is to request it, else 0. */
uint32_t drive_phase_check(drive_phase_check_t *p, const drive_phase_view_t *v);

#endif
