/*
 * plant.h - the host-side plant: PM synchronous machine, three-phase
 * two-level inverter with DC link, mechanics and sensors. Plain C, double
 * precision, no firmware headers: hal/sil and sil/runner bridge it to the
 * drive.
 *
 * Timing (docs/architecture.md): plant_step() advances one PWM period
 * [t, t+Ts) with one set of duties. The carrier is a triangle with its
 * valley at t and t+Ts and its peak at t+Ts/2; phase x's high-side switch is
 * commanded on while carrier > 1 - duty_x (pulse centred at t+Ts/2).
 * plant_sample() returns the sensors at the valley, i.e. at plant time t.
 */
#ifndef FD_PLANT_PLANT_H
#define FD_PLANT_PLANT_H

#include <stdbool.h>
#include <stdint.h>

#include "plant_magnetics.h"
#include "profile.h"

/* The phase inductance matrix the star point sees (Fabbri 2022, (3.3)):
 * self L0 + L2 cos(2 theta_e - k 2pi/3), mutual M0 + M2 cos(...), k per
 * phase as printed there. Given by its mutual terms beside ld, lq:
 *   L0 = (ld + lq)/2 + m0,   L2 = (ld - lq) - 2 m2,
 * so that its alpha-beta part is exactly the dq model the plant integrates
 * (ld = L0 - M0 + L2/2 + M2, lq = L0 - M0 - L2/2 - M2) and the DFC
 * anisotropy is p = b/a = (ld - lq)/(ld + lq) (3.7), whatever the split;
 * the split sets the signal amplitude a of (3.7) (docs/star-point.md).
 * phi_self, phi_mut: the self (L2) and mutual (M2) terms' 2theta axes
 * shifted with load, independently: 2 theta_e -> 2 theta_e + phi_self i_q
 * in the self terms, 2 theta_e + phi_mut i_q in the mutual ones. (3.7)
 * with L2, M2 as phasors L2 e^{j phi_self i_q}, M2 e^{j phi_mut i_q} gives
 * the Full IVD model (3.97) exactly (plant_aniso_load): phi_a = arg(L2 -
 * M2), phi_b = phi_a + arg(L2/2 + M2), p = |L2/2 + M2| / (L0 - M0). Equal
 * shifts phi: phi_a = phi i_q, phi_b = 2 phi i_q (a turned saliency axis).
 * amp_iq: the amplitude of their 2theta terms with load, L2 and M2 times
 * (1 + amp_iq |i_q|) (a and b of (3.97) change with it).
 * Both act on the star point only (the dq model keeps ld, lq). */
typedef struct {
  int enabled;              /* 0: isotropic star point (the mean of the leg potentials) */
  double m0, m2;            /* [H] */
  double phi_self, phi_mut; /* [rad/A] */
  double amp_iq;            /* [1/A] */
  /* the range of the load scale 1 + amp_iq |i_q| the plant uses (clamped
   * to it) and plant_aniso_ok checks; 0: 0.5 .. 2 (the scenario parser
   * sets it from the current the plant may carry, controller.i_trip) */
  double k_min, k_max;
  double shift; /* [rad electrical]: the star point's saliency axis turned by this, 2 theta_e ->
                   2 (theta_e + shift): the position it shows is off by it (inject.star_shift) */
} plant_aniso_t;

typedef struct {
  int pole_pairs;
  double rs;       /* stator phase resistance [Ohm] */
  double ld, lq;   /* [H] */
  double lambda_m; /* PM flux linkage (peak, per phase) [Vs] */
  /* d-axis magnet saturation (linear machines; plant_magnetics.h): the
   * incremental d inductance ld / (1 + ld_sat tanh(x / i_sat)), x the d
   * current of the unsaturated machine: lower where the d current adds to
   * the magnet's flux, higher where it opposes it. ld_sat 0: none */
  double ld_sat; /* [0, 0.5] */
  double i_sat;  /* [A] > 0 */
  /* NULL: linear (ld, lq, lambda_m); else the saturated machine's flux map
   * (plant_fluxmap.h; ld, lq, lambda_m unused), owned by the caller */
  const plant_fluxmap_t *map;
  plant_aniso_t aniso; /* linear machines only */
} plant_machine_t;

typedef enum { PLANT_INV_AVERAGE, PLANT_INV_SWITCHING } plant_inverter_model_t;

typedef struct {
  plant_inverter_model_t model;
  double dead_time; /* [s] */
  int substeps;     /* integration steps per PWM period (average model), >= 1 */
  /* device voltage drops of every leg (both models; plant_inverter_sw.c):
   * a conducting switch drops v_th_sw + r_on_sw |i|, a conducting diode
   * v_f_diode + r_diode |i|, the thresholds taken in over the smooth-sign
   * band of the currents (plant_inverter.c); all 0: ideal devices */
  double v_th_sw;   /* [V] */
  double r_on_sw;   /* [Ohm] */
  double v_f_diode; /* [V] */
  double r_diode;   /* [Ohm] */
} plant_inverter_t;

/* IDEAL: stiff source. RC: source behind r charging c, both ways.
 * RECTIFIER: the same through a diode (a diode rectifier): the source only
 * supplies, braking energy stays in c. An optional braking chopper (a
 * resistor r_chop switched on above v_chop_on, off below v_chop_off, by
 * the board's own comparator, decided at each period start) acts on RC and
 * RECTIFIER links. */
typedef enum { PLANT_DC_IDEAL, PLANT_DC_RC, PLANT_DC_RECTIFIER } plant_dc_kind_t;

typedef struct {
  plant_dc_kind_t kind;
  double v_source;   /* source voltage [V] */
  double r;          /* source resistance [Ohm] (RC only) */
  double c;          /* DC-link capacitance [F] (RC only) */
  double r_chop;     /* braking chopper resistance [Ohm], 0: none */
  double v_chop_on;  /* the chopper switches on above [V] */
  double v_chop_off; /* and off below [V] (< v_chop_on) */
} plant_dclink_t;

typedef enum { PLANT_MECH_FREE, PLANT_MECH_IMPOSED } plant_mech_mode_t;

typedef struct {
  plant_mech_mode_t mode;
  double j;              /* inertia [kg m^2] */
  double b;              /* viscous friction [N m s/rad] */
  profile_t load_torque; /* load torque opposing motion [N m] (FREE mode) */
  profile_t speed;       /* imposed mechanical speed [rad/s] (IMPOSED mode) */
  double theta0;         /* initial mechanical angle [rad] */
  double omega0;         /* initial mechanical speed [rad/s] (FREE mode) */
  /* cogging torque on the rotor (FREE mode; plant_mech.c):
   * T_cog = cog_amp sin(cog_order theta_m + cog_phase); cog_amp 0: none */
  double cog_amp;   /* [N m] */
  int cog_order;    /* periods per mechanical turn */
  double cog_phase; /* [rad] */
} plant_mech_t;

typedef struct {
  int adc_bits;           /* e.g. 12 */
  double i_full_scale;    /* current ADC range is +-i_full_scale [A] */
  double v_full_scale;    /* DC-link ADC range is 0..v_full_scale [V] */
  double gain_error[3];   /* relative gain error per current channel */
  double offset_error[3]; /* offset per current channel [A] */
  double i_noise;         /* white noise rms on each current [A] */
  double v_noise;         /* white noise rms on the DC-link voltage [V] */
  int encoder_cpr;        /* encoder counts per mechanical revolution, 0 = ideal */
  /* star-point channel (w.r.t. the DC-link midpoint): bipolar ADC of
   * adc_bits over +-star_full_scale (0: v_full_scale / 2), behind a
   * first-order measurement circuit of time constant star_tau */
  double star_full_scale; /* [V] */
  double star_gain_error; /* relative */
  double star_offset;     /* [V] */
  double star_noise;      /* white noise rms [V] */
  double star_tau;        /* [s], 0: none */
  uint32_t seed;          /* noise generator seed */
} plant_sensors_t;

/* Plant-parameter faults the controller is not told of (plant_faults.c).
 * Profiles evaluated at each period start and held over the period (the
 * RK4 stages see one set of parameters); a profile with no terms: none.
 * Their bounds (profile_bounds) are checked: the scales stay positive (the
 * PM's may reach 0), the friction terms non-negative. */
typedef struct {
  profile_t rs_scale;       /* R_s times this (winding temperature) */
  profile_t lambda_m_scale; /* PM flux linkage times this (demagnetisation; linear machines) */
  profile_t c_scale;        /* DC-link capacitance times this (capacitor loss; RC link) */
  profile_t star_shift; /* [rad electrical] the star point's axis turned (plant_aniso_t.shift) */
  /* passive load (FREE mechanics): a friction that always opposes motion
   * and never drives the rotor: Coulomb torque [N m] (at standstill it
   * holds the rotor against a net torque up to its value) and viscous
   * friction [N m s/rad] added to mech.b */
  profile_t coulomb, viscous;
} plant_faults_t;

typedef struct {
  plant_machine_t machine;
  plant_inverter_t inverter;
  plant_dclink_t dclink;
  plant_mech_t mech;
  plant_sensors_t sensors;
  double ts;             /* PWM period [s] */
  plant_faults_t faults; /* injected parameter faults */
} plant_params_t;

/* What the sensors deliver at the sampling instant (converted back to SI
 * with nominal gains, exactly as a board would). */
typedef struct {
  double i_abc[3];
  double v_dc;
  double v_star;    /* star-point voltage w.r.t. the DC-link midpoint [V] */
  double enc_angle; /* mechanical angle, quantised, [0, 2pi) */
} plant_adc_t;

/* True (noise-free) state, for logs and tests. */
typedef struct {
  double t;            /* plant time [s] */
  double i_abc[3];     /* [A] */
  double i_dq[2];      /* rotor frame currents [A] */
  double lambda_dq[2]; /* rotor frame flux linkages [Vs] */
  double v_abc[3];     /* period-average phase-to-neutral voltages, last step [V] */
  double theta_m;      /* mechanical angle [rad], wrapped to [0, 2pi) */
  double theta_e;      /* electrical angle [rad], wrapped to [0, 2pi) */
  double omega_m;      /* mechanical speed [rad/s] */
  double torque;       /* electromagnetic torque [N m] */
  double load_torque;  /* load torque in force [N m] */
  double v_dc;         /* DC-link capacitor voltage [V] */
  double i_dc;         /* period-average DC-link current drawn [A] */
  double torque_avg;   /* period average of the torque, last step [N m] */
  double i_dq_avg[2];  /* period averages of the rotor-frame currents, last step [A] */
} plant_state_t;

#define PLANT_ZIG_N    128 /* layers of the ziggurat normal generator */
#define PLANT_STAR_MAX 2   /* star-point samples per period */

/* True currents of one state, cached (plant_machine.c): valid while the
 * state equals the key (lambda_d, lambda_q, theta_m) bit for bit. */
typedef struct {
  double key[3];
  double th_e, c, s; /* pole_pairs * theta_m (not wrapped), its cos and sin */
  double i_dq[2], i_abc[3];
} plant_cur_cache_t;

/* The part of the true state that run metrics need every period
 * (plant_get_brief; the torque, needed over the run's tail only, from
 * plant_get_torque). */
typedef struct {
  double i_abc[3]; /* [A] */
  double omega_m;  /* [rad/s] */
  double v_dc;     /* [V] */
} plant_brief_t;

/* Power-stage faults (switching inverter model, plant_inverter_sw.c).
 * Switch bit of leg x (0..2): PLANT_SW_LOW(x), PLANT_SW_HIGH(x). */
#define PLANT_SW_LOW(x)  (1u << (2 * (x)))
#define PLANT_SW_HIGH(x) (1u << (2 * (x) + 1))
typedef struct {
  unsigned open;       /* switches that never conduct (their diodes still do); both
                          of a leg: the leg's gate signals lost, it floats */
  unsigned closed;     /* switches that conduct whatever the gates (at most one per leg) */
  unsigned phase_open; /* bit x: phase x's lead disconnected (its current is zero,
                          its terminal floats) */
  unsigned ground;     /* bit x: phase x's lead shorted to earth, which is the
                          link's negative rail (bolted: the leg's output tied to it) */
  unsigned shorted;    /* two bits: those phases' leads shorted together (bolted),
                          0: none */
} plant_power_fault_t;

/* Internal working data of plant_t (constants precomputed by plant_init,
 * caches and the memory of the switching-level inverter). Not part of the
 * API: read the state through plant_get_state(). */
typedef struct {
  /* constants */
  plant_mag_t mag;            /* the magnetic model (plant_magnetics.h) */
  double inv_j, inv_c, inv_r; /* 1/J, 1/C, 1/R */
  int one_way;                /* the link's source only supplies (RECTIFIER) */
  int chop_on;                /* the braking chopper conducts this period */
  double g_chop;              /* its conductance this period [S] */
  double kdt;                 /* dead_time / ts */
  double inv_ts;              /* 1 / ts */
  double inv_band;  /* 1 / width of the smooth sign of the average-model dead time [1/A] */
  uint64_t n_steps; /* periods done: t = n_steps * ts exactly */
  int steps;        /* integration steps of this period (>= inverter.substeps) */
  int too_fast;     /* a period began beyond the speed the steps can cover */
  /* switching-level inverter memory, per leg: time of the last commanded
   * edge relative to the start of the next period (<= 0), commanded
   * high-side state after it, diode conduction state of a floating leg */
  double edge_t[3];
  int edge_cmd[3];
  int cond[3];
  int all_zero; /* all phase currents blocked by the diodes */
  /* power-stage faults in force (plant_set_power_faults), any of them set;
   * a shoot-through ended by the gate driver since the last
   * plant_take_desat() (healthy switches held off while set) */
  plant_power_fault_t pf;
  int pf_any;
  int desat;
  int gates_prev; /* gates were on during the last period */
  double v_star;  /* star-point voltage at the last valley (see plant_sample) */
  /* star-point samples (plant_star.c): requested instants of the next
   * period, the measurement circuit's output there (w.r.t. the negative
   * rail, before the ADC), the circuit's state */
  int star_n;
  double star_t[PLANT_STAR_MAX], star_v[PLANT_STAR_MAX];
  double star_vf;
  double l0, l2; /* the (3.3) matrix (aniso.enabled) [H] */
  /* mechanical input profile (plant_internal.h): equal to m_val for
   * t in [m_t0, m_t1) */
  double m_val, m_t0, m_t1;
  plant_cur_cache_t cur;
  int carry_n;
  int avgs;      /* integrate the period averages (plant_set_averages) */
  double we_max; /* plant_speed_limit_e */
  /* parameter faults (plant_faults.c): on at all, the nominal values they
   * scale, the Coulomb torque of this period (added to the mechanical
   * input), its direction of motion (+-1; 0: the rotor is held) */
  int faults_on;
  double rs0, lambda_m0, inv_c0, b0;
  double fric, th_start;
  int fric_dir; /* periods since cur's cos/sin last came from libm */
  /* sensor constants (plant_sensors.c) */
  double adc_levels, adc_ilsb, adc_vlsb, enc_step;
  double adc_gain[3], adc_code_max, adc_i_off; /* 1 + gain_error, levels - 1, levels / 2 */
  /* ziggurat tables of the noise generator (plant_sensors.c) */
  uint32_t zig_k[PLANT_ZIG_N];
  double zig_w[PLANT_ZIG_N], zig_f[PLANT_ZIG_N];
  int drops; /* any device drop of the inverter is not 0 (plant_inverter_t) */
} plant_aux_t;

typedef struct {
  plant_params_t p;
  /* state */
  double t;
  double lambda_d, lambda_q; /* rotor frame flux linkages [Vs] */
  double theta_m, omega_m;
  double v_dc;
  double v_abc_avg[3];
  double i_dc_avg;
  double torque_avg, i_dq_avg[2]; /* period averages of the last step */
  uint64_t rng;
  plant_aux_t aux; /* internal */
} plant_t;

/* After plant_init, only pl->p.dclink.v_source may be changed (between
 * steps); the other parameters are fixed (constants and caches derive from
 * them). The state members may be set between steps (tests do). */

/* Validates the parameters; on error returns a negative number and sets
 * *field to the name of the offending parameter (static string). */
int plant_check(const plant_params_t *p, const char **field);
/* The fewest integration steps per period that keep the explicit RK4
 * stable and monotone on the machine's fastest electrical mode: h R_s /
 * L_min <= PLANT_HR_MAX (L_min the smallest incremental inductance, the
 * flux map's for a map machine). plant_check refuses fewer (field
 * "inverter.substeps"). Needs a valid machine and ts. */
#define PLANT_HR_MAX       0.5
#define PLANT_SUBSTEPS_MAX 64
/* The RC link's pole: h / (R C) <= PLANT_HC_MAX (RK4 is stable to 2.78;
 * the default 0.1 Ohm, 470 uF link at 16 kHz is 1.33 with one step). With
 * the faults, R_s and C at the extremes of their scale profiles' bounds. */
#define PLANT_HC_MAX 2.0
/* Largest device drops of the inverter (plant_inverter_t): thresholds
 * [V], resistances [Ohm]. */
#define PLANT_V_DROP_MAX 5.0
#define PLANT_R_DROP_MAX 10.0
/* Bounds of the cogging torque (plant_mech_t): amplitude [N m], order,
 * phase [rad]. */
#define PLANT_COG_AMP_MAX   1e4
#define PLANT_COG_ORDER_MAX 1000
#define PLANT_COG_PHASE_MAX 7.0
/* Largest scales of the parameter faults (plant_faults_t). */
#define PLANT_RS_SCALE_MAX       4.0
#define PLANT_LAMBDA_M_SCALE_MAX 2.0
#define PLANT_C_SCALE_MAX        10.0
#define PLANT_STAR_SHIFT_MAX     7.0 /* [rad electrical]: inject.star_shift within +-this */
/* The electromechanical mode (the rotor's inertia against the PM flux's
 * stiffness, w_em = p psi_m sqrt(1.5 / (L_min J)), psi_m the PM flux at its
 * largest scale), the friction's pole (b / J, the passive load's viscous
 * term at its largest included) and the cogging torque's stiffness
 * (w_cog = sqrt(A N / J), plant_mech.c) count too: h w_em <= PLANT_HW_MAX,
 * h b / J <= PLANT_HC_MAX, h w_cog <= PLANT_HW_MAX. A tiny inertia needs more than
 * PLANT_SUBSTEPS_MAX: the scenario is refused (mechanics.j). */
int plant_substeps_needed(const plant_params_t *p);
/* The RC link's share of it alone (1 for an ideal link). */
int plant_substeps_link(const plant_params_t *p);
/* Its mechanical share alone (1 when the speed is imposed). */
int plant_substeps_mech(const plant_params_t *p);
/* Speed: the rotor frame turns against the stationary-frame voltages at
 * w_e = p w_m, and the flux's transient oscillates at w_e: each period is
 * integrated in at least ceil(|w_e| Ts / PLANT_HW_MAX) steps (|w_m| at the
 * period's start, plus what the load alone adds over it, free; imposed
 * the larger of its start and end), at most
 * PLANT_STEPS_SPEED_MAX; beyond that the plant stops advancing
 * (plant_too_fast) rather than diverge. Without it RK4 leaves its
 * stability region at |w_e| h = 2.83 (issue 22: 47.6 kA after an active
 * short at -19,564 rpm on the Rubino SPM, 2.69 rad per period). */
#define PLANT_HW_MAX          0.5
#define PLANT_STEPS_SPEED_MAX 256
/* The steps of the last period; the electrical speed [rad/s] beyond which
 * a period is not integrated (PLANT_STEPS_SPEED_MAX PLANT_HW_MAX / Ts). */
int plant_steps_last(const plant_t *pl);
double plant_speed_limit_e(const plant_t *pl);
/* True once a period started beyond plant_speed_limit_e: the state is the
 * last one integrated (finite), the run must end (sil_run reports it). */
bool plant_too_fast(const plant_t *pl);
/* Initialises (calls plant_check first). Returns 0 or the error. */
int plant_init(plant_t *pl, const plant_params_t *p, const char **field);
/* Advances one PWM period with the given duties (clamped to [0, 1]),
 * centred pulses. gates_on = false: all six switches off, only the diodes
 * conduct. */
void plant_step(plant_t *pl, const double duty[3], bool gates_on);
/* The same with a pattern: leg x's high side commanded on over
 * [on[x], off[x]) in fractions of the period (0 <= on <= off <= 1). The
 * average model uses the duty off - on. */
void plant_step_pattern(plant_t *pl, const double on[3], const double off[3], bool gates_on);
/* Star-point samples during the next plant_step_pattern (switching
 * inverter model), at instants t_req [s] from its start, ascending, inside
 * (0, ts); n <= PLANT_STAR_MAX (0: none). Read them after the step with
 * plant_star_read(): the measurement circuit's output through the star
 * channel's ADC, w.r.t. the DC-link midpoint [V]; returns their number
 * (the average model has no switching instants: it returns the period
 * average of the star point for each). */
void plant_star_request(plant_t *pl, int n, const double t_req[]);
int plant_star_read(plant_t *pl, double v[PLANT_STAR_MAX]);
/* Whether a machine's (3.3) matrix is an inductance matrix (positive
 * definite at every angle) that carries the position (L2 != M2). */
int plant_aniso_ok(const plant_machine_t *m);
/* ... and at the load i_q: the scale and the self / mutual shifts apart */
int plant_aniso_ok_at(const plant_machine_t *m, double i_q);
/* a and b of (3.7) (normalised to v_dc) of a machine's (3.3) matrix. */
void plant_aniso_ab(const plant_machine_t *m, double *a, double *b);
/* The Full IVD model (3.97) of the star point at the load i_q: the phase
 * shifts phi_a, phi_b [rad] of its 2theta and 4theta terms and its
 * anisotropy p = b/a, with the load scale (clamped as the plant does). */
void plant_aniso_load(const plant_machine_t *m, double i_q, double *phi_a, double *phi_b,
                      double *p);
/* The static star-point divider G_c = L_Sigma / (L_Sigma T^T) of (2.90)
 * at electrical angle theta_e and q current i_q (isotropic: 1/3 each). */
void plant_star_gain(const plant_t *pl, double theta_e, double i_q, double g[3]);
/* Sensor readings at the present plant time (the carrier valley). */
void plant_sample(plant_t *pl, plant_adc_t *out);
/* The same, and plant_get_brief() of the same state into br: the currents'
 * cache checked once (the runner's sample and its metrics, every period). */
void plant_sample_brief(plant_t *pl, plant_adc_t *out, plant_brief_t *br);
void plant_get_state(const plant_t *pl, plant_state_t *out);
/* Whether the average model integrates the period averages of the phase
 * voltages, the DC-link current, the torque and the rotor-frame currents
 * (plant_t's v_abc_avg, i_dc_avg, torque_avg, i_dq_avg; plant_state_t's
 * v_abc, i_dc, torque_avg, i_dq_avg): on after plant_init. Off, they read
 * NaN (and are not integrated by the average model): for a caller that
 * never reads them (the runner without an observer, `--bench`); the
 * state's evolution is the same, bit for bit. */
void plant_set_averages(plant_t *pl, bool on);
/* Power-stage faults from the next plant_step on (between steps; all zero:
 * healthy). They act on the switch-level circuit: with gates on they need
 * the switching model (the average model's periods are routed to it while
 * any is set). Returns -1 (nothing changed) for two stuck-closed switches
 * in one leg, a short of other than two leads, or a short with an open
 * lead. */
int plant_set_power_faults(plant_t *pl, const plant_power_fault_t *f);
/* A shoot-through since the last call: a stuck-closed switch's partner was
 * commanded on. The gate driver's desaturation detection turns that switch
 * off again within its blanking time (taken as zero: the shoot-through
 * current, which bypasses the machine, is not integrated) and holds every
 * healthy switch off; the caller latches its fault output (nFAULT).
 * Returns and clears the flag. */
bool plant_take_desat(plant_t *pl);
/* The same values as plant_get_state() for the members of plant_brief_t,
 * cheaply: the currents are computed once per state and shared with
 * plant_sample() (hence not const). */
void plant_get_brief(plant_t *pl, plant_brief_t *out);
/* plant_get_state()'s torque [N m], as cheaply. */
double plant_get_torque(plant_t *pl);

#endif
