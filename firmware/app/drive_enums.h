/*
 * drive_enums.h - the drive's named values, each an X-macro list that is
 * the single source of the C enum, its names (logs, JSON, scenario keys)
 * and, through `fluxdrive-sil --print-params`, the DBC value tables and
 * the Python tools (tools/src/fluxdrive/params.py). Values are the list
 * order (fault bits: 1 << order); append, never reorder.
 */
#ifndef FLUXDRIVE_DRIVE_ENUMS_H
#define FLUXDRIVE_DRIVE_ENUMS_H

/* clang-format off */
/* Control laws: X(ENUM, name, doc). The law table (ctrl.c, generated from
 * this list) has one row ctrl_law_<name> per entry, in this order. */
#define DRIVE_LAW_LIST(X)                                                                  \
  X(FOC, foc, "rotor-frame PI current control; torque mode on the MTPA trajectory")       \
  X(PI_DFVC, pi_dfvc, "PI direct flux vector control of SPM machines (Rubino 2020, IV.7)") \
  X(DB_DFVC, db_dfvc, "deadbeat direct flux vector control of SPM machines (Rubino 2020)") \
  X(DFVC_DECOUPLED, dfvc_decoupled,                                                         \
    "decoupled DFVC of saturated machines, online MTPA/MTPV (Varatharajan 2022)")

/* Control modes: X(ENUM, name, doc). */
#define DRIVE_MODE_LIST(X)                                                    \
  X(TORQUE, torque, "torque reference")                                       \
  X(SPEED, speed, "the speed loop produces the torque reference")            \
  X(CURRENT, current, "d-q current references (laws with CTRL_CAP_CURRENT)")

/* Drive states: X(ENUM, name, doc). */
#define DRIVE_STATE_LIST(X)                                                          \
  X(IDLE, idle, "gates off, waiting for enable")                                    \
  X(OFFSET_CAL, offset_cal, "gates off, averaging the current-sensor offsets")      \
  X(RUN, run, "gates on, control law active")                                       \
  X(FAULT, fault, "gates off, causes latched until cleared")                        \
  X(ALIGN, align, "gates on, d current along the assumed axis (position sources)")     \
  X(IDENT, ident, "gates on, an identification procedure the host asked for (commissioning)")

/* Fault causes, bit n = list position n: X(ENUM, name, doc). */
#define DRIVE_FAULT_LIST(X)                                                                     \
  X(OVERCURRENT, overcurrent, "a phase current sample above i_trip")                           \
  X(OVERVOLTAGE, overvoltage, "DC link above v_dc_max")                                        \
  X(UNDERVOLTAGE, undervoltage, "DC link below v_dc_min while the gates are on")               \
  X(OVERSPEED, overspeed, "speed estimate above speed_trip")                                   \
  X(HW_OVERCURRENT, hw_overcurrent, "the board's break input tripped (gates off in hardware)") \
  X(OFFSET, offset, "a current-sensor offset beyond offset_max")                               \
  X(CONTROL, control, "the control law reported a fault (non-finite state, flux collapse)")    \
  X(CMD_TIMEOUT, cmd_timeout, "no command or heartbeat from the host in time (CAN)")           \
  X(SAMPLE, sample, "a non-finite or incomplete ADC sample set")                               \
  X(POSITION, position, "the position source is invalid or implausible")                       \
  X(LOST_CONTROL, lost_control, "loss of control: current, load angle, tracking or observer")  \
  X(WATCHDOG, watchdog, "the MCU was reset by the watchdog (latched at start-up)")             \
  X(CONFIG, config, "the parameter set in force was refused (law unavailable)")                  \
  X(CURRENT_SENSOR, current_sensor, "the three measured phase currents do not sum to zero (a gain, an offset, a lost channel)") \
  X(OVERRUN, overrun, "the PWM-period interrupt overran its period repeatedly (overrun_k of the last overrun_n slow periods)") \
  X(GATE_DRIVER, gate_driver, "the gate driver's fault output (nFAULT: desaturation / shoot-through, supply undervoltage) on the break-2 input: gates off in hardware")

/* Position sources: X(ENUM, ident, "name", doc); ident names the source's
 * row (pos_source_<ident>), "name" is what scenarios, logs and CAN use.
 * The source table (pos_sources.c) has one row per entry, in this order. */
#define POS_SOURCE_LIST(X) \
  X(ENCODER, encoder, "encoder", "encoder (quantised, half-count corrected) and PLL")                                    \
  X(DFC, dfc, "dfc", "star point: standard Direct Flux Control (3.8)-(3.10) and PLL")                                     \
  X(DFC_INV, dfc_inv, "dfc_inv", "star point: inverse DFC (3.15)-(3.16) and PLL")                                         \
  X(IVD, ivd, "ivd", "star point: DFC with Iterative Vector Decoupling (3.76), Full IVD (3.100) with phase shifts, and PLL") \
  X(DFC_KF, dfc_kf, "dfc+kf", "star point: standard DFC and the Kalman filter on speed, angle, load torque (4.46)-(4.49)")   \
  X(IVD_KF, ivd_kf, "ivd+kf", "star point: IVD / Full IVD and the Kalman filter on speed, angle, load torque (4.46)-(4.49)") \
  X(EKF, ekf, "ekf", "star point: extended Kalman filter on the DFC signals (4.35)-(4.41), a and b known")                \
  X(IVD_KF_RLS, ivd_kf_rls, "ivd+kf+rls", "star point: IVD and Kalman filter with a, b identified online by RLS (4.51)-(4.57), Fig. 4.4")
/* clang-format on */

#define DRIVE_ENUM_LAW(E, n, d)       DRIVE_LAW_##E,
#define DRIVE_ENUM_MODE(E, n, d)      DRIVE_MODE_##E,
#define DRIVE_ENUM_STATE(E, n, d)     DRIVE_STATE_##E,
#define DRIVE_ENUM_FAULT_BIT(E, n, d) DRIVE_FAULT_BIT_##E,
#define DRIVE_ENUM_POS(E, n, s, d)    POS_SOURCE_##E,

typedef enum { DRIVE_LAW_LIST(DRIVE_ENUM_LAW) DRIVE_LAW_COUNT } drive_law_t;
typedef enum { DRIVE_MODE_LIST(DRIVE_ENUM_MODE) DRIVE_MODE_COUNT } drive_mode_t;
typedef enum { DRIVE_STATE_LIST(DRIVE_ENUM_STATE) DRIVE_STATE_COUNT } drive_state_t;
typedef enum { DRIVE_FAULT_LIST(DRIVE_ENUM_FAULT_BIT) DRIVE_FAULT_COUNT } drive_fault_bit_t;
typedef enum { POS_SOURCE_LIST(DRIVE_ENUM_POS) POS_SOURCE_COUNT } pos_source_t;

/* Fault masks: DRIVE_FAULT_OVERCURRENT = 1u << DRIVE_FAULT_BIT_OVERCURRENT ... */
#define DRIVE_ENUM_FAULT_MASK(E, n, d) DRIVE_FAULT_##E = 1u << DRIVE_FAULT_BIT_##E,
enum { DRIVE_FAULT_LIST(DRIVE_ENUM_FAULT_MASK) DRIVE_FAULT_ALL = (1u << DRIVE_FAULT_COUNT) - 1u };

/* Names ("?" out of range). */
const char *drive_law_name(unsigned law);
const char *drive_mode_name(unsigned mode);
const char *drive_state_name(unsigned state);
const char *drive_pos_source_name(unsigned src);
/* Name of the lowest set fault bit, "none" for 0. */
const char *drive_fault_name(unsigned fault_bits);
/* Index of name in a list, or -1. */
int drive_law_index(const char *name);
int drive_mode_index(const char *name);
int drive_pos_source_index(const char *name);

#endif
