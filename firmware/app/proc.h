/*
 * proc.h - procedures as laws: the drive's start-up procedures (offset
 * calibration, the encoder's alignment, the held start) behind one table,
 * beside the law table (ctrl.h), as ODrive makes its calibrations control
 * laws (PhaseControlLaw, ResistanceMeasurementControlLaw).
 *
 * A procedure is a row {name, id, state shown, capabilities, check, wanted,
 * init, step, abort, publish} (proc_row_t): check says whether a parameter
 * set and position source can run it (the main loop's validation), wanted
 * whether the start wants it with that set, init starts
 * it, step runs one PWM period in the ISR and returns running, done or
 * failed (with the fault bits), abort stops it (disable, trip), publish
 * writes its progress and results into the procedure telemetry. Its state
 * lives in a union (proc_state_t; one procedure runs at a time, as one law
 * does). A step sees the period through a narrow view (proc_in_t: the
 * sample, the offset-corrected currents, the voltage available, the
 * position source's estimate) and asks for a voltage (proc_out_t); the
 * drive modulates it and writes the pattern through the HAL, as for a
 * law. Its voltage is bounded by the voltage available (v_max) and its
 * current by the parameter set's (align_current, i_max), so a procedure
 * cannot ask for more than the run may; the drive's protections stay in
 * force while it runs. A procedure hands its result over where it is
 * used, through its setup's sinks (the current offsets in force, the
 * position source's reference), when its step returns PROC_DONE.
 *
 * The start sequence (proc_start_sequence) is a list of ids: the drive
 * runs each row that applies (wanted, and its check passes: proc_applies)
 * in turn, the gates coming on before the first that modulates, then the
 * law; the sequence lists the gates-off procedures first.
 *
 * Adding a procedure: its module (proc_<name>.c with its row), its state
 * in proc_state_t, one line in PROC_LIST, and its id in the sequence if
 * the start runs it (proc.c; docs/architecture.md, "Adding a procedure").
 * Every function of a procedure is FD_COLD (flash on the board): the ISR
 * runs it only while it is in force, never in the run.
 */
#ifndef FLUXDRIVE_PROC_H
#define FLUXDRIVE_PROC_H

#include <stdbool.h>
#include <stdint.h>

#include "control/current_ctrl.h"
#include "drive_config.h"
#include "hal.h"
#include "math/frames.h"
#include "model/machine.h"
#include "pos_source.h"

/* X(ENUM, name, description): one line per procedure, its row is
 * proc_<name> (proc_<name>.c). */
#define PROC_LIST(X)                                                                               \
  X(OFFSET, offset, "current sensor offsets with the gates off (offset_samples averaged)")         \
  X(ALIGN, align, "d current along theta = 0 for align_time; an encoder's: damped, until settled") \
  X(HOLD, hold, "the held start (start_mode 1): angle at standstill, polarity from two d pulses")  \
  X(RS, rs,                                                                                        \
    "identification: R_s and the inverter's voltage error v_err(i) from DC levels, both signs")    \
  X(LDQ, ldq,                                                                                      \
    "identification: L_d, L_q at standstill, square-wave voltage injection along d, then q")       \
  X(FMAP, fmap, "flux maps at standstill: bipolar i_q on an i_d bias per grid point (issue 25 c)") \
  X(POLES, poles,                                                                                  \
    "identification: pole pairs and polarity, a current vector turned slowly (encoder)")           \
  X(ENC, enc, "identification: encoder offset and direction, the rotor held at angles both ways")  \
  X(FLUX, flux, "identification: PM flux lambda_m at id_speed both ways (encoder, current loop)")  \
  X(MECH, mech,                                                                                    \
    "identification: inertia J, Coulomb and viscous friction from torque steps (encoder)")         \
  X(STAR, star,                                                                                    \
    "identification: the star point's a, b (3.7), the rotor turned half an electrical turn")

#define PROC_ENUM(E, n, d) PROC_##E,
typedef enum { PROC_LIST(PROC_ENUM) PROC_COUNT } proc_id_t;
#undef PROC_ENUM
#define PROC_NONE PROC_COUNT /* no procedure in force */

/* What a step returns. */
enum { PROC_RUNNING = 0, PROC_DONE = 1, PROC_FAILED = 2 };

/* The procedure telemetry's status (proc_telemetry_t.status). */
enum {
  PROC_ST_IDLE = 0, /* none has run since start-up */
  PROC_ST_RUNNING = 1,
  PROC_ST_DONE = 2,
  PROC_ST_FAILED = 3,
  PROC_ST_ABORTED = 4, /* disabled, stopped or tripped by another cause while it ran */
  PROC_ST_REFUSED = 5  /* an identification the parameter set in force cannot run (its check) */
};

enum {
  PROC_CAP_GATES = 1u << 0, /* modulates: the gates are on while it runs */
  /* an identification procedure: the host may run it alone, with the drive
   * disabled (drive_cmd_identify; the commissioning, docs/commissioning.md):
   * the offsets first, then it, then the gates off again */
  PROC_CAP_IDENT = 1u << 1
};

/* Results published like telemetry (drive_telemetry_t.proc): the last
 * procedure that ran, where it is, what it found. */
#define PROC_RESULTS 8
typedef struct {
  uint8_t id;     /* proc_id_t (PROC_NONE: none yet) */
  uint8_t status; /* PROC_ST_* */
  uint8_t phase;  /* the procedure's own phase (the held start's: acquisition, pulses ...) */
  uint32_t n;     /* periods since it began */
  uint32_t fault; /* PROC_ST_FAILED: the fault bits it raised */
  /* its results (0 until found; each row's publish documents its own,
   * docs/commissioning.md the identification's): offset: the three offsets [A]; align:
   * the angle of the current (the source's reference once done) [rad
   * electrical], the periods the rotor has been calm; hold: the angle along the
   * pulses, the north pole's angle [rad electrical], the evidence
   * (d0 - d1) / mean; fmap: the last grid point done (proc_fmap.c); star: a, b, p = b / a (3.7)
   * (after the first sweep's fit that sweep's, at the end the mean of both), the rotor's angle
   * where the last fitted sweep ended [rad electrical], the fit's rms
   * residual / |a| (the larger of the sweeps'), the sweeps' difference in
   * a and in b over |a|, the first sweep's lag of the rotor behind the
   * current vector [rad electrical] (docs/commissioning.md) */
  float result[PROC_RESULTS];
} proc_telemetry_t;

/* What every procedure reads, and where it hands its result over (the
 * drive's, ISR-owned; built by the drive for each call). */
typedef struct {
  const drive_config_t *cfg;
  const machine_t *machine;
  const pos_source_row_t *pos_src;
  pos_state_t *pos_st; /* the source: align / hold give it its reference */
  float *offset;       /* [3] the current offsets in force [A] (offset calibration) */
  float *i_sum_noise;  /* the current-sum check's noise floor [A] (offset calibration) */
  bool gated;          /* the source measures through the DFC window */
} proc_setup_t;

/* One period as a procedure sees it. */
typedef struct {
  const hal_sample_t *s;     /* the sample set as read (raw currents) */
  ab_t i_ab;                 /* offset-corrected (and window-corrected) currents [A] */
  float v_max;               /* voltage amplitude it may ask: v_margin x linear range [V] */
  const pos_estimate_t *pos; /* the position source's estimate this period */
} proc_in_t;

typedef struct {
  ab_t v_ab;      /* voltage for the next period [V], |v_ab| <= v_max */
  bool apply;     /* write the pattern of v_ab (false: nothing written this period) */
  bool plain;     /* the pattern without the DFC window (a clean sample) */
  uint32_t fault; /* PROC_FAILED: the fault bits (DRIVE_FAULT_*) */
} proc_out_t;

/* The encoder's alignment's timing (proc_align.c), from the parameter set:
 * the damping and when the rotor counts as settled. */
typedef struct {
  float kd;            /* the damping: angle of the current per electrical rad/s [s] */
  float w_calm;        /* settled: |speed| below this [rad/s electrical] ... */
  uint32_t calm_need;  /* ... for this many periods */
  uint32_t still_need; /* ... or from the start for this many */
  uint32_t n_timeout;  /* not settled after this many periods: position fault */
} proc_align_timing_t;

/* The alignment's state: its timing (proc_align_timing) is derived from
 * the parameter set at each step, not kept (a start's few ms in flash; the
 * union stays at the size the drive's layout keeps, drive.h). */
typedef struct {
  current_ctrl_t cc; /* the d current's loop (alpha-beta frame at theta = 0) */
  uint32_t n;        /* periods since it began */
  uint32_t calm_n;   /* periods the encoder's speed has stayed below w_calm */
  float phi;         /* the current's angle last period [rad] */
} proc_align_t;

typedef struct {
  float acc[3];
  float sum1, sum2; /* the current sum's samples: their sum and sum of squares */
  uint32_t n;
} proc_offset_t;

typedef struct {
  uint8_t phase;           /* proc_hold.c: PH_* */
  uint16_t n;              /* periods into the phase */
  uint32_t n_all;          /* periods since it began */
  float theta;             /* the estimate's angle the pulses are applied along [rad] */
  float theta_out;         /* the north pole's angle found [rad] */
  float i0;                /* the d current when a pulse began [A] */
  float di[2];             /* the d current each pulse built, along theta and theta + pi [A] */
  uint8_t n_pulse, n_zero; /* periods of each pulse and of the way back (proc_hold.c) */
  dq_t v_prev;             /* the voltage asked last period, in the estimate's frame [V] */
  bool plain;              /* the pattern without the DFC window (a pulse's clean sample) */
} proc_hold_t;

/* The ldq identification's alignment (proc_ldq.c): the current's
 * angle at period n of it: pi/2 for n_first periods (a rotor anywhere but
 * at -pi/2 turns there), then turned to 0 over n_turn (a rotor left at
 * -pi/2 is 90 degrees off the current then, and follows too), then 0. A
 * rotor that starts at pi, where a current along 0 holds it unstably (the
 * rs procedure leaves it there), is aligned all the same. */
static inline float proc_ident_align_angle(uint32_t n, uint32_t n_first, uint32_t n_turn) {
  if (n < n_first) {
    return 0.5f * FRAMES_PI;
  }
  const uint32_t k = n - n_first;
  return k < n_turn ? 0.5f * FRAMES_PI * (1.0f - (float)k / (float)n_turn) : 0.0f;
}

/* The free rotor's swing about a DC current (proc_swing.c): the voltage
 * across the current, filtered, and its turning points (its sign changes),
 * where a window over which the swing's back-EMF averages out begins and
 * ends. */
typedef struct {
  float v;     /* the voltage across the current, filtered [V] */
  float v_x;   /* ... and along it [V] */
  float i_y;   /* the damping current across it, slew-limited [A] (proc_swing_damping) */
  int8_t sign; /* v's sign (0: none yet) */
  bool turned; /* it changed sign this period: a turning point */
} proc_swing_t;

/* proc_rs.c: R_s and v_err(i) (issue 25 a). Levels of each sign, at most: */
#define PROC_RS_LEVELS_MAX 8u
typedef struct {
  current_ctrl_t cc;  /* the level's current loop (frame turned by theta) */
  machine_t loop;     /* its machine: linear, the smaller inductance on both axes */
  uint8_t n_levels;   /* levels of each sign (id_rs_levels) */
  uint8_t phase;      /* proc_rs.c's phases */
  int8_t last;        /* the last level measured (-1: none) */
  uint32_t n;         /* periods into the phase */
  uint32_t n_all;     /* periods since it began */
  float i_ref;        /* the current reference, slew-limited [A] */
  float theta;        /* the current's axis [rad] */
  float v_prev;       /* the axis' voltage asked last period [V] */
  float acc_v, acc_i; /* the level's sums */
  uint32_t acc_n;     /* ... of this many periods */
  proc_swing_t swing; /* the swing's turning points (proc_swing.c) */
  bool open;          /* the level's window has begun (at a turning point) */
  float i_peak;       /* the largest measured current amplitude [A] */
  float lv_i[2u * PROC_RS_LEVELS_MAX]; /* the levels' mean current, positive then negative [A] */
  float lv_v[2u * PROC_RS_LEVELS_MAX]; /* ... and commanded voltage [V] */
  float res[PROC_RESULTS];             /* the fit (proc_rs.c, rs_publish) */
} proc_rs_t;

/* proc_ldq.c: L_d, L_q at standstill (issue 25 b). A half wave of at most
 * PROC_LDQ_M_MAX PWM periods (id_ldq_freq at least f_pwm / 32): */
#define PROC_LDQ_M_MAX 16u
typedef struct {
  current_ctrl_t cc;            /* the bias current's loop (alignment, hold) */
  uint8_t phase;                /* proc_ldq.c's phases */
  uint8_t axis;                 /* 0: d (the bias' axis), 1: q */
  uint8_t tries;                /* amplitude adjustments of this axis */
  uint32_t n;                   /* periods into the phase */
  uint32_t n_all;               /* periods since it began */
  float i_ref;                  /* the bias reference, slew-limited [A] */
  proc_swing_t swing;           /* the alignment's swing, seen across the current (proc_swing.c) */
  float v_hold[2];              /* the bias' voltage (d, q) held under the injection [V] */
  float v_h;                    /* the injection's amplitude [V] */
  float i_prev;                 /* the injected axis' current last period [A] */
  float acc_d;                  /* the bias current's sum over an injection period [A] */
  float w[2u * PROC_LDQ_M_MAX]; /* the current summed at each of the wave's periods (5) [A] */
  uint32_t sn;                  /* ... over this many waves */
  float i_lo, i_hi;             /* the injected axis' current range [A] */
  float i_peak;                 /* the largest measured current amplitude [A] */
  float l[2];                   /* the inductances found (d, q) [H] */
  float ripple[2];              /* their current ripple, peak to peak [A] */
  float cross[2];               /* the other axis' ripple over this axis' [-] */
  float o_lo, o_hi;             /* the other axis' current range under the injection [A] */
  /* the least squares of (5) of an axis measured, a few of the wave's
   * positions a period over the periods after it (proc_ldq.c,
   * ldq_solve_step; on w, which q's trials leave alone): d's during q's
   * trials, q's before done */
  uint32_t sns;   /* ... over this many waves */
  float g[6];     /* the normal equations' matrix (00 01 02 11 12 22) */
  float h[3];     /* ... their right-hand side */
  float mw;       /* the wave's mean [A] */
  float v_hs;     /* the injection's amplitude of the axis solved [V] */
  uint8_t sj;     /* positions summed so far */
  uint8_t s_axis; /* the axis solved */
  bool solving;   /* a least squares in progress */
} proc_ldq_t;
/* The flux maps' state (proc_fmap.c): the point, its half cycle and
 * segment, the integrals of (1) and their averages (2), the sums (3). */
typedef struct {
  current_ctrl_t cc;       /* the dq current loop on the source's angle */
  uint32_t n;              /* periods since it began */
  uint16_t point;          /* grid index of the point in force (k nd + j) */
  uint16_t m;              /* periods into the segment */
  uint8_t half;            /* half cycle of the point: even i_q = +I, odd -I */
  uint8_t seg;             /* at the point, back at zero, its results shown */
  uint8_t phase;           /* published: 1 + the point in force */
  float theta;             /* the d axis [rad electrical] */
  dq_t v_prev;             /* the voltage asked last period [V] */
  dq_t i_prev;             /* the current last period [A] */
  dq_t phi, q;             /* int (v - R i) dt [Vs], int i dt [As] over the half */
  dq_t phi1, q1, i1;       /* their sums over the point's last quarter dwell */
  dq_t phi2, q2;           /* ... and over the zero's */
  float acc[4];            /* the point's sums over its halves: psi_d, psi_q, i_d, i_q */
  float res[PROC_RESULTS]; /* the last point done (publish) */
} proc_fmap_t;
/* The encoder identifications' shared view of the encoder (proc_poles.c):
 * the mechanical angle unwrapped from their start [rad]. */
typedef struct {
  float prev;  /* the last reading [rad mechanical, 0 .. 2 pi) */
  float theta; /* unwrapped from the start [rad mechanical] */
  bool started;
} proc_enc_unwrap_t;

/* proc_poles.c: a current vector of amplitude i turned slowly (I-f). */
typedef struct {
  current_ctrl_t cc;   /* the current loop in the alpha-beta frame */
  proc_enc_unwrap_t u; /* the encoder */
  uint32_t n, n_all;   /* periods into the phase, since it began */
  uint8_t phase;       /* proc_poles.c: PH_* */
  float theta_v;       /* the vector's angle [rad electrical] */
  float acc;           /* sum of the unwrapped angle over the hold's window */
  uint32_t acc_n;
  float th0, th1; /* the rotor's rest angle before and after the turns [rad mechanical] */
  float pp;       /* pole pairs measured (not rounded), signed by the direction */
} proc_poles_t;

/* proc_enc.c: the rotor held at angles both ways. */
typedef struct {
  current_ctrl_t cc;
  proc_enc_unwrap_t u;
  uint32_t n, n_all;
  uint8_t point;      /* the hold point: 0 .. 2 PROC_ENC_POINTS - 1 (forward, then back) */
  float theta_v;      /* the vector's angle asked (before the damping) [rad electrical] */
  float th_start;     /* the unwrapped angle at the forward pass's first point [rad mechanical] */
  float move;         /* the unwrapped movement of the forward pass [rad mechanical] */
  float s[2][2];      /* sum of (cos, sin) of (encoder - vector) per direction */
  float e[2];         /* the offset found per direction [rad electrical] */
  float acc_c, acc_s; /* the point's sums */
  uint32_t acc_n;
  float dir; /* +1, -1: the encoder counts with the vector's angle or against it */
} proc_enc_t;

/* proc_flux.c: the rotor spun by the current loop on the encoder. */
typedef struct {
  current_ctrl_t cc;
  proc_enc_unwrap_t u;
  uint32_t n, n_all;
  uint8_t phase;
  float w_ref;  /* the speed reference [rad/s mechanical] */
  float th0;    /* the unwrapped angle at the window's start [rad mechanical] */
  float sum[4]; /* over the window: v_d, v_q, i_d, i_q */
  uint32_t sum_n;
  float lam[2], w[2]; /* lambda_m and the speed [rad/s electrical] per direction */
  uint8_t limited;    /* the voltage limit was reached in a window */
  dq_t v_prev;        /* the voltage asked last period [V], rotor frame */
} proc_flux_t;

/* proc_mech.c: torque steps on the encoder; the least squares in core
 * (estimation/ident_mech.h). The signals are filtered by a moving mean of
 * PROC_MECH_NB blocks of PROC_MECH_D periods (the encoder's speed over it). */
#define PROC_MECH_D  32u /* periods per block */
#define PROC_MECH_NB 16u /* blocks in the moving mean */
typedef struct {
  current_ctrl_t cc;
  proc_enc_unwrap_t u;
  uint32_t n, n_all;
  uint8_t phase;
  uint16_t rows;            /* the least squares' rows so far */
  uint32_t bk;              /* blocks so far */
  float r_th[PROC_MECH_NB]; /* the angle at the last blocks' ends [rad mechanical] */
  float r_t[PROC_MECH_NB];  /* the torque's integral over each block [N m s] */
  float r_s[PROC_MECH_NB];  /* sgn(w)'s integral over each block [s] */
  float b_t, b_th0;         /* this block's torque integral, its start angle */
  float x_prev[3];          /* the filtered speed, sgn(w), torque at the last block */
  float w0;                 /* the filtered speed at the window's start [rad/s] */
  float win[3];             /* over the window: int sgn(w), int w, int T (filtered) */
  uint32_t win_n;           /* blocks in the window */
  float res[4];             /* J, T_c, B, the fit's residual */
  float w;                  /* the speed [rad/s mechanical] (the PLL's) */
  uint8_t plat;             /* the constant-speed plateau in force (proc_mech.c) */
  bool plat_meas;           /* ... measured (settled) */
  union {
    float ls[10];       /* the steps: the normal equations (ident_mech.h) */
    struct {            /* the plateaus (J solved): */
      float integ;      /* the speed loop's integral [A] */
      float p_t, p_th0; /* the plateau's torque integral [N m s], its start angle [rad] */
      float ps[5];      /* the sums s s, s w, w w, s T, w T (T = T_c s + B w) */
    } pl;
  };
} proc_mech_t;
/* The star point's a, b (proc_star.c): the signals of a sweep in
 * PROC_STAR_BINS bins of the current vector's angle, then their fit. */
#define PROC_STAR_BINS 32u
typedef struct {
  float y[PROC_STAR_BINS][2]; /* each bin's mean -Gamma_alpha + j Gamma_beta (/ v_dc) */
  float g_acc[3];             /* the bin in force: each test vector's signals summed */
  uint16_t g_n[3];            /* and counted */
  uint8_t phase;              /* proc_star.c: PH_* */
  uint8_t bin;                /* the bin in force (sweep) or fitted (fit) */
  uint8_t pass;               /* the fit's pass (0: the start) */
  bool done;
  uint32_t n;        /* periods into the phase */
  uint32_t n_all;    /* periods since it began */
  current_ctrl_t cc; /* the current vector's loop (the stator frame) */
  float a, b;        /* the fit in progress */
  float lag[2];      /* e^{-j2 delta}: the rotor's lag behind the vector */
  float h[3];        /* the reduced normal matrix (00, 01, 11) */
  float acc[4];      /* the pass's sums (the start's A, B; the gradient and the lag) */
  float res2;        /* the pass's squared residuals */
  float swing;       /* the alignment's rotor movement (the source's speed integrated) [rad] */
  float dir;         /* the sweeps' direction: +1 (0 -> pi) or -1 (0 -> -pi) */
  float theta_end;   /* the rotor's angle where the sweep ended [rad electrical] */
  float sw[2][4];    /* each sweep's a, b, lag [rad electrical], rms residual / |a| */
} proc_star_t;

typedef union {
  proc_offset_t offset;
  proc_align_t align;
  proc_hold_t hold;
  proc_rs_t rs;
  proc_ldq_t ldq;
  proc_fmap_t fmap;
  proc_poles_t poles;
  proc_enc_t enc;
  proc_flux_t flux;
  proc_mech_t mech;
  proc_star_t star;
} proc_state_t;

typedef struct {
  const char *name;
  proc_id_t id;
  uint8_t state; /* the drive state shown while it runs (drive_state_t) */
  uint32_t caps; /* PROC_CAP_* */
  /* NULL when the parameter set and source can run it, else why not
   * (*field: the parameter); NULL check: always */
  const char *(*check)(const proc_setup_t *su, const char **field);
  /* whether the start wants it with this set (it may still be unable:
   * check); NULL: always */
  bool (*wanted)(const proc_setup_t *su);
  void (*init)(proc_state_t *st, const proc_setup_t *su);
  /* one period: PROC_RUNNING, PROC_DONE (result handed over) or
   * PROC_FAILED (out->fault); writes every field of *out */
  int (*step)(proc_state_t *st, const proc_setup_t *su, const proc_in_t *in, proc_out_t *out);
  void (*abort)(proc_state_t *st); /* NULL: nothing to undo */
  /* progress and results (tm->id and tm->status are the drive's) */
  void (*publish)(const proc_state_t *st, proc_telemetry_t *tm);
} proc_row_t;

#define PROC_ROW_DECLARE(E, n, d) extern const proc_row_t proc_##n;
PROC_LIST(PROC_ROW_DECLARE)
#undef PROC_ROW_DECLARE

/* The row of a procedure (NULL out of range). */
const proc_row_t *proc_row(proc_id_t id);
/* The start: the procedures the drive runs from an enable to the run, in
 * order (*n of them). */
const proc_id_t *proc_start_sequence(unsigned *n);
/* The identification run of `id` (drive_cmd_identify): the offsets, then
 * the procedure; *n entries written to seq[2]. */
void proc_ident_sequence(proc_id_t id, proc_id_t seq[2], unsigned *n);
/* Whether the host may run `id` alone (PROC_CAP_IDENT): NULL, or why not. */
const char *proc_ident_refusal(proc_id_t id, const proc_setup_t *su, const char **field);
/* Whether the start runs `id` with this setup: wanted and able (check). */
bool proc_applies(proc_id_t id, const proc_setup_t *su);
/* Every procedure of the start that is wanted must be able: NULL, or the
 * first refusal (*field: the parameter). The main loop's validation
 * (drive_config_usable). */
const char *proc_start_refusal(const proc_setup_t *su, const char **field);

/* proc_align.c: the alignment's timing for cfg (also the tests'). */
void proc_align_timing(const drive_config_t *cfg, float lambda_m, proc_align_timing_t *t);

/* proc_swing.c: reset before the first period; step once a period with
 * the voltage across the current asked the period before [V] and the
 * period ts [s]: sets turned at the swing's turning points. */
void proc_swing_reset(proc_swing_t *w);
void proc_swing_step(proc_swing_t *w, float v_x, float v_y, float ts);
float proc_swing_damping(proc_swing_t *w, float i_x, float bound, float slew, bool on);

/* proc_poles.c: the encoder identifications' test current (id_i_test, 0:
 * 0.3 i_max, at most i_max) [A], their speed bound (id_speed_max, 0: 0.3
 * speed_max) and measuring speed (id_speed, 0: 0.2 speed_max, at most the
 * bound) [rad/s mechanical]; the encoder unwrapped (returns the angle). */
float proc_id_current(const drive_config_t *cfg);
float proc_id_speed_max(const drive_config_t *cfg);
float proc_id_speed(const drive_config_t *cfg);
void proc_enc_unwrap_reset(proc_enc_unwrap_t *u);
float proc_enc_unwrap(proc_enc_unwrap_t *u, float enc_angle);
/* Refused without an encoder (the encoder identifications' check). */
const char *proc_id_encoder_check(const proc_setup_t *su, const char **field);

#endif /* FLUXDRIVE_PROC_H */
