/*
 * scenario_key_table.h - the rows of scenario_keys.h's table, as an
 * X-macro: X(ID, .field = value, ...) with the fields of scenario_key_t.
 * Expanded once, in scenario.c, where the setters, the hooks and the
 * parser's context (ctx_t: AT_CTX) are. Rows in reading order; an object's
 * rows follow it. Ranges and defaults are those the parser applies; the
 * doc column is the one line docs/scenarios.md shows (the sections below
 * the reference there say more).
 */
#ifndef FD_SIL_SCENARIO_KEY_TABLE_H
#define FD_SIL_SCENARIO_KEY_TABLE_H

#define AT(kind, member)     .at = SK_AT_##kind, .offset = offsetof(scenario_t, member)
#define AT_CTX(kind, member) .at = SK_AT_CTX_##kind, .offset = offsetof(ctx_t, member)
#define RANGE(l, h)          .lo = (l), .hi = (h)
#define DEF(v)               .has_def = 1, .def = (v)
#define PARAM(name)          .range = SK_RANGE_PARAM, .param = (name)

/* a power-stage fault: {SEL: one of NAMES, "active": profile} (inject);
 * SEL also inside a string, FIELD a member designator */
/* NOLINTBEGIN(bugprone-macro-parentheses) */
#define POWER_FAULT(X, ID, KEY, SEL, NAMES, HINT, DOC)                                             \
  X(ID, .parent = K_INJECT, .key = (KEY), .type = SK_OBJECT, .doc = (DOC))                         \
  X(ID##_SEL, .parent = (ID), .key = (SEL), .type = SK_ENUM, .names = (NAMES), .req = (HINT),      \
    AT(INT, ID##_FIELD.target), .doc = "the " SEL " it acts on")                                   \
  X(ID##_ACTIVE, .parent = (ID), .key = "active", .type = SK_PROFILE,                              \
    .req = "a profile: the fault acts while it is > 0.5", AT(PROFILE, ID##_FIELD.active),          \
    .doc = "acts while > 0.5")

/* a CAN direction of inject.can (socketcand) */
#define CAN_DIR(X, ID, KEY, FIELD, DOC)                                                            \
  X(ID, .parent = K_I_CAN, .key = (KEY), .type = SK_OBJECT, .post = can_dir_post,                  \
    .offset = offsetof(scenario_t, FIELD), .doc = (DOC))                                           \
  X(ID##_LOSS, .parent = (ID), .key = "loss", .type = SK_BOUNDED, RANGE(0.0, 1.0),                 \
    AT(PROFILE, FIELD.loss), .dflt = "0", .doc = "probability that a frame is lost")               \
  X(ID##_EVERY, .parent = (ID), .key = "every", .type = SK_INT, RANGE(0.0, 1e6),                   \
    AT(U32, FIELD.every), DEF(0.0), .doc = "every n-th frame lost (0 none, n >= 2)")               \
  X(ID##_DELAY, .parent = (ID), .key = "delay", .type = SK_BOUNDED, RANGE(0.0, SIL_CAN_DELAY_MAX), \
    AT(PROFILE, FIELD.delay), .dflt = "0", .doc = "latency [s]")                                   \
  X(ID##_JITTER, .parent = (ID), .key = "jitter", .type = SK_BOUNDED,                              \
    RANGE(0.0, SIL_CAN_DELAY_MAX), AT(PROFILE, FIELD.jitter), .dflt = "0",                         \
    .doc = "extra latency, uniform in [0, jitter] [s]")
/* NOLINTEND(bugprone-macro-parentheses) */

#define K_I_SWITCH_OPEN_FIELD   switch_open
#define K_I_SWITCH_CLOSED_FIELD switch_closed
#define K_I_PHASE_LOST_FIELD    phase_lost
#define K_I_PHASE_OPEN_FIELD    phase_open
#define K_I_PHASE_SHORT_FIELD   phase_short
#define K_I_GROUND_SHORT_FIELD  ground_short

#define SK_PROFILE_DOC(what) .type = SK_PROFILE, .dflt = "none", .doc = (what)

/* clang-format off */
#define SCENARIO_KEYS(X)                                                                           \
  X(K_ROOT, .parent = -1, .key = "", .type = SK_OBJECT, .set = root_pre, .doc = "the scenario")                     \
  X(K_NAME, .parent = K_ROOT, .key = "name", .type = SK_STRING, .set = set_name,                   \
    .dflt = "unnamed", .doc = "shown in summaries and plot titles (valid UTF-8, at most 95 bytes)") \
  X(K_DESCRIPTION, .parent = K_ROOT, .key = "description", .type = SK_STRING, .dflt = "",          \
    .doc = "free text")                                                                            \
  X(K_DURATION, .parent = K_ROOT, .key = "duration", .type = SK_NUM, RANGE(1e-4, 3600.0),          \
    AT(F64, duration), .req = "simulated time in seconds", .doc = "simulated time [s]")            \
  /* ---- machine ---- */                                                                          \
  X(K_MACHINE, .parent = K_ROOT, .key = "machine", .type = SK_OBJECT, .set = machine_pre,          \
    .post = machine_post, .doc = "the machine: a preset, a flux map, its parameters")              \
  X(K_M_PRESET, .parent = K_MACHINE, .key = "preset", .type = SK_STRING, .by_hook = 1,             \
    .dflt = "rubino2020_spm", .doc = "a machine preset (below): plant, estimates, limits")         \
  X(K_M_MAP, .parent = K_MACHINE, .key = "map", .type = SK_STRING, .by_hook = 1, .dflt = "none",   \
    .doc = "a flux-map file (.fdmap, .npz, .csv): a saturated machine")                            \
  X(K_M_POLE_PAIRS, .parent = K_MACHINE, .key = "pole_pairs", .type = SK_INT,                      \
    PARAM("pole_pairs"), AT(INT, plant.machine.pole_pairs), .dflt = "preset",                      \
    .doc = "pole pairs")                                                                           \
  X(K_M_RS, .parent = K_MACHINE, .key = "rs", .type = SK_NUM, PARAM("rs"),                         \
    AT(F64, plant.machine.rs), .dflt = "preset", .doc = "stator resistance [Ohm]")                 \
  X(K_M_LS, .parent = K_MACHINE, .key = "ls", .type = SK_NUM, PARAM("ld"), AT_CTX(F64, ls),        \
    .dflt = "none", .doc = "sets ld = lq (SPM) [H]; not with ld, lq")                              \
  X(K_M_LD, .parent = K_MACHINE, .key = "ld", .type = SK_NUM, PARAM("ld"),                         \
    AT(F64, plant.machine.ld), .dflt = "preset", .doc = "d inductance [H]")                        \
  X(K_M_LQ, .parent = K_MACHINE, .key = "lq", .type = SK_NUM, PARAM("lq"),                         \
    AT(F64, plant.machine.lq), .dflt = "preset", .doc = "q inductance [H]")                        \
  X(K_M_LAMBDA_M, .parent = K_MACHINE, .key = "lambda_m", .type = SK_NUM, PARAM("lambda_m"),       \
    AT(F64, plant.machine.lambda_m), .dflt = "preset", .doc = "PM flux linkage [Vs]")              \
  X(K_M_LD_SAT, .parent = K_MACHINE, .key = "ld_sat", .type = SK_NUM, RANGE(0.0, 0.5),             \
    AT(F64, plant.machine.ld_sat), .dflt = "0 (none)",                                             \
    .doc = "the magnet's d-axis saturation (linear machines); needs i_sat")                        \
  X(K_M_I_SAT, .parent = K_MACHINE, .key = "i_sat", .type = SK_NUM, RANGE(1e-3, 1e4),              \
    AT(F64, plant.machine.i_sat), .dflt = "none", .doc = "its current scale [A]")                  \
  X(K_M_STAR_M0, .parent = K_MACHINE, .key = "star_m0", .type = SK_NUM, RANGE(-1.0, 1.0),          \
    AT(F64, plant.machine.aniso.m0), .dflt = "preset",                                             \
    .doc = "star point (3.3): mutual term M0 [H]")                                                 \
  X(K_M_STAR_M2, .parent = K_MACHINE, .key = "star_m2", .type = SK_NUM, RANGE(-1.0, 1.0),          \
    AT(F64, plant.machine.aniso.m2), .dflt = "preset", .doc = "star point (3.3): M2 [H]")          \
  X(K_M_STAR_PHI_SELF, .parent = K_MACHINE, .key = "star_phi_self", .type = SK_NUM,                \
    RANGE(-1.0, 1.0), AT(F64, plant.machine.aniso.phi_self), .dflt = "0",                          \
    .doc = "shift of the self 2theta terms with i_q [rad/A]")                                      \
  X(K_M_STAR_PHI_MUTUAL, .parent = K_MACHINE, .key = "star_phi_mutual", .type = SK_NUM,            \
    RANGE(-1.0, 1.0), AT(F64, plant.machine.aniso.phi_mut), .dflt = "0",                           \
    .doc = "shift of the mutual 2theta terms with i_q [rad/A]")                                    \
  X(K_M_STAR_AMP_IQ, .parent = K_MACHINE, .key = "star_amp_iq", .type = SK_NUM,                    \
    RANGE(-0.5, 1.0), AT(F64, plant.machine.aniso.amp_iq), .dflt = "0",                            \
    .doc = "scale of the 2theta terms with abs(i_q) [1/A]")                                        \
  X(K_M_STAR_PHI_IQ, .parent = K_MACHINE, .key = "star_phi_iq", .type = SK_NUM,                    \
    RANGE(-1.0, 1.0), AT_CTX(F64, star_phi_iq), .dflt = "none",                                    \
    .doc = "sets star_phi_self and star_phi_mutual both; not with them")                           \
  X(K_M_STAR_P, .parent = K_MACHINE, .key = "star_p", .type = SK_NUM,                              \
    RANGE(-0.999999, 0.999999), AT_CTX(F64, star_p), .dflt = "none",                               \
    .doc = "anisotropy p of (3.7), keeping L0, M0, L2; not with ld, lq, star_m2")                  \
  X(K_M_COG_AMP, .parent = K_MACHINE, .key = "cogging_amp", .type = SK_NUM,                        \
    RANGE(-PLANT_COG_AMP_MAX, PLANT_COG_AMP_MAX), AT(F64, plant.mech.cog_amp), .dflt = "0 (none)", \
    .plant_field = "mech.cog_amp", .doc = "cogging torque amplitude A [N m]; needs cogging_order") \
  X(K_M_COG_ORDER, .parent = K_MACHINE, .key = "cogging_order", .type = SK_INT,                    \
    RANGE(1.0, PLANT_COG_ORDER_MAX), AT(INT, plant.mech.cog_order), .dflt = "none",                \
    .plant_field = "mech.cog_order", .doc = "its periods N per mechanical turn")                   \
  X(K_M_COG_PHASE, .parent = K_MACHINE, .key = "cogging_phase", .type = SK_NUM,                    \
    RANGE(-PLANT_COG_PHASE_MAX, PLANT_COG_PHASE_MAX), AT(F64, plant.mech.cog_phase), .dflt = "0",  \
    .plant_field = "mech.cog_phase", .doc = "its phase phi [rad]: A sin(N theta_m + phi)")         \
  /* ---- inverter ---- */                                                                         \
  X(K_INVERTER, .parent = K_ROOT, .key = "inverter", .type = SK_OBJECT, .post = inverter_post,     \
    .doc = "the inverter model, PWM frequency, dead time")                                         \
  X(K_INV_MODEL, .parent = K_INVERTER, .key = "model", .type = SK_ENUM, .names = inverter_models,  \
    AT(INT, plant.inverter.model), DEF(0.0), .doc = "period-average or switch-level model")        \
  X(K_INV_DEAD_TIME, .parent = K_INVERTER, .key = "dead_time", .type = SK_NUM,                     \
    PARAM("dead_time"), AT(F64, plant.inverter.dead_time), DEF(1e-6), .doc = "dead time [s]")      \
  X(K_INV_SUBSTEPS, .parent = K_INVERTER, .key = "substeps", .type = SK_INT,                       \
    RANGE(1.0, PLANT_SUBSTEPS_MAX), AT(INT, plant.inverter.substeps), DEF(0.0),                    \
    .dflt = "automatic", .doc = "RK4 steps per period (fewer than needed: refused)")               \
  X(K_INV_PWM_FREQUENCY, .parent = K_INVERTER, .key = "pwm_frequency", .type = SK_NUM,             \
    .range = SK_RANGE_PARAM_INV, .param = "ts", .set = set_pwm_frequency, DEF(16000.0),            \
    .plant_field = "ts", .doc = "PWM and ISR frequency [Hz]")                                      \
  X(K_INV_HW_TRIP, .parent = K_INVERTER, .key = "hw_trip", .type = SK_NUM, RANGE(0.0, 1e5),        \
    AT(F64, hw_trip), .dflt = "0 (none)", .doc = "hardware overcurrent comparator [A], latched")   \
  X(K_INV_V_TH_SW, .parent = K_INVERTER, .key = "v_th_sw", .type = SK_NUM,                         \
    RANGE(0.0, PLANT_V_DROP_MAX), AT(F64, plant.inverter.v_th_sw), DEF(0.0),                       \
    .doc = "a conducting switch's threshold voltage [V]")                                          \
  X(K_INV_R_ON_SW, .parent = K_INVERTER, .key = "r_on_sw", .type = SK_NUM,                         \
    RANGE(0.0, PLANT_R_DROP_MAX), AT(F64, plant.inverter.r_on_sw), DEF(0.0),                       \
    .doc = "its on-resistance [Ohm]")                                                              \
  X(K_INV_V_F_DIODE, .parent = K_INVERTER, .key = "v_f_diode", .type = SK_NUM,                     \
    RANGE(0.0, PLANT_V_DROP_MAX), AT(F64, plant.inverter.v_f_diode), DEF(0.0),                     \
    .doc = "a conducting diode's forward voltage [V]")                                             \
  X(K_INV_R_DIODE, .parent = K_INVERTER, .key = "r_diode", .type = SK_NUM,                         \
    RANGE(0.0, PLANT_R_DROP_MAX), AT(F64, plant.inverter.r_diode), DEF(0.0),                       \
    .doc = "its resistance [Ohm]")                                                                 \
  X(K_INV_R_DEV, .parent = K_INVERTER, .key = "r_dev", .type = SK_NUM, PARAM("r_dev"),             \
    AT(F32, drive.r_dev), .dflt = "(r_on_sw + r_diode) / 2",                                       \
    .doc = "the board's stated device resistance [Ohm] (the drive's r_dev)")                      \
  /* ---- dc_link ---- */                                                                          \
  X(K_DC_LINK, .parent = K_ROOT, .key = "dc_link", .type = SK_OBJECT,                              \
    .doc = "the DC source, link capacitor, rectifier, chopper")                                    \
  X(K_DC_KIND, .parent = K_DC_LINK, .key = "kind", .type = SK_ENUM, .names = dc_kinds,             \
    AT(INT, plant.dclink.kind), DEF(0.0), .plant_field = "dclink.kind",                            \
    .doc = "ideal source, r-c link, or the same through a diode")                                  \
  X(K_DC_VOLTAGE, .parent = K_DC_LINK, .key = "voltage", .type = SK_PROFILE, AT(PROFILE, v_source),\
    .dflt = "preset", .plant_field = "dclink.v_source",                                            \
    .doc = "source voltage profile [V]; in (0, 1e4] at t = 0")                                     \
  X(K_DC_R, .parent = K_DC_LINK, .key = "r", .type = SK_NUM, RANGE(0.0, 1e6),                      \
    AT(F64, plant.dclink.r), DEF(0.1), .plant_field = "dclink.r",                                  \
    .doc = "series resistance [Ohm] (rc, rectifier)")                                              \
  X(K_DC_C, .parent = K_DC_LINK, .key = "c", .type = SK_NUM, RANGE(0.0, 10.0),                     \
    AT(F64, plant.dclink.c), DEF(470e-6), .plant_field = "dclink.c",                               \
    .doc = "link capacitance [F] (rc, rectifier)")                                                 \
  X(K_DC_CHOPPER_R, .parent = K_DC_LINK, .key = "chopper_r", .type = SK_NUM, RANGE(0.0, 1e6),      \
    AT(F64, plant.dclink.r_chop), .dflt = "0 (none)", .plant_field = "dclink.r_chop",              \
    .doc = "braking chopper resistance [Ohm]")                                                     \
  X(K_DC_CHOPPER_ON, .parent = K_DC_LINK, .key = "chopper_on", .type = SK_NUM, RANGE(0.0, 1e4),    \
    AT(F64, plant.dclink.v_chop_on), .dflt = "0", .plant_field = "dclink.v_chop_on",               \
    .doc = "chopper on above [V]")                                                                 \
  X(K_DC_CHOPPER_OFF, .parent = K_DC_LINK, .key = "chopper_off", .type = SK_NUM, RANGE(0.0, 1e4),  \
    AT(F64, plant.dclink.v_chop_off), .dflt = "0", .plant_field = "dclink.v_chop_off",             \
    .doc = "chopper off below [V]")                                                                \
  /* ---- mechanics ---- */                                                                        \
  X(K_MECHANICS, .parent = K_ROOT, .key = "mechanics", .type = SK_OBJECT,                          \
    .post = mechanics_post, .doc = "the rotor and its load, or a dynamometer")                     \
  X(K_MECH_MODE, .parent = K_MECHANICS, .key = "mode", .type = SK_ENUM, .names = mech_modes,       \
    AT(INT, plant.mech.mode), DEF(0.0), .plant_field = "mech.mode",                                \
    .doc = "free rotor, or the speed imposed (needs speed)")                                       \
  X(K_MECH_J, .parent = K_MECHANICS, .key = "j", .type = SK_NUM, PARAM("inertia"),                 \
    AT(F64, plant.mech.j), .dflt = "preset", .plant_field = "mech.j", .doc = "inertia [kg m^2]")   \
  X(K_MECH_B, .parent = K_MECHANICS, .key = "b", .type = SK_NUM, PARAM("friction"),                \
    AT(F64, plant.mech.b), .dflt = "preset", .plant_field = "mech.b",                              \
    .doc = "viscous friction [N m s/rad]")                                                         \
  X(K_MECH_LOAD_TORQUE, .parent = K_MECHANICS, .key = "load_torque", .type = SK_PROFILE,           \
    AT(PROFILE, plant.mech.load_torque), .dflt = "0", .doc = "load torque [N m]")                  \
  X(K_MECH_SPEED, .parent = K_MECHANICS, .key = "speed", .type = SK_PROFILE,                       \
    AT(PROFILE, plant.mech.speed), .dflt = "none", .doc = "imposed speed, mechanical [rad/s]")     \
  X(K_MECH_THETA0, .parent = K_MECHANICS, .key = "theta0", .type = SK_NUM, RANGE(-1e3, 1e3),       \
    AT(F64, plant.mech.theta0), .dflt = "0", .plant_field = "mech.theta0",                         \
    .doc = "initial angle [rad mech]")                                                             \
  X(K_MECH_SPEED0, .parent = K_MECHANICS, .key = "speed0", .type = SK_NUM, RANGE(-1e5, 1e5),       \
    AT(F64, plant.mech.omega0), .dflt = "0", .plant_field = "mech.omega0",                         \
    .doc = "initial speed [rad/s mech]")                                                           \
  /* ---- sensors ---- */                                                                          \
  X(K_SENSORS, .parent = K_ROOT, .key = "sensors", .type = SK_OBJECT, .post = sensors_post,        \
    .doc = "ADCs, encoder, star-point channel")                                                    \
  X(K_S_ADC_BITS, .parent = K_SENSORS, .key = "adc_bits", .type = SK_INT, RANGE(8.0, 24.0),        \
    AT(INT, plant.sensors.adc_bits), DEF(12.0), .doc = "ADC resolution [bits]")                    \
  X(K_S_I_FULL_SCALE, .parent = K_SENSORS, .key = "i_full_scale", .type = SK_NUM,                  \
    RANGE(1e-3, 1e5), AT(F64, plant.sensors.i_full_scale), .dflt = "preset",                       \
    .doc = "current ADC range +- [A]; above controller.i_trip")                                    \
  X(K_S_V_FULL_SCALE, .parent = K_SENSORS, .key = "v_full_scale", .type = SK_NUM,                  \
    RANGE(1e-3, 1e5), AT(F64, plant.sensors.v_full_scale), .dflt = "preset",                       \
    .doc = "DC-link ADC range [V]; above controller.v_dc_max")                                     \
  X(K_S_I_NOISE, .parent = K_SENSORS, .key = "i_noise", .type = SK_NUM, RANGE(0.0, 1e3),           \
    AT(F64, plant.sensors.i_noise), DEF(0.0), .doc = "current noise rms [A]")                      \
  X(K_S_V_NOISE, .parent = K_SENSORS, .key = "v_noise", .type = SK_NUM, RANGE(0.0, 1e3),           \
    AT(F64, plant.sensors.v_noise), DEF(0.0), .doc = "DC-link voltage noise rms [V]")              \
  X(K_S_ENCODER_CPR, .parent = K_SENSORS, .key = "encoder_cpr", .type = SK_INT, .lo = 0.0,         \
    .range = SK_RANGE_PARAM_HI, .param = "enc_cpr", AT(INT, plant.sensors.encoder_cpr),            \
    DEF(4096.0), .doc = "encoder counts per revolution, 0 = ideal")                                \
  X(K_S_SEED, .parent = K_SENSORS, .key = "seed", .type = SK_INT, RANGE(0.0, 2147483647.0),        \
    AT(U32, plant.sensors.seed), DEF(1.0), .doc = "noise generator seed")                          \
  X(K_S_STAR_FULL_SCALE, .parent = K_SENSORS, .key = "star_full_scale", .type = SK_NUM,            \
    RANGE(0.0, 1e5), AT(F64, plant.sensors.star_full_scale), .dflt = "v_full_scale / 2",           \
    .doc = "star-point channel range +- [V] around the DC midpoint")                               \
  X(K_S_STAR_NOISE, .parent = K_SENSORS, .key = "star_noise", .type = SK_NUM, RANGE(0.0, 1e3),     \
    AT(F64, plant.sensors.star_noise), .dflt = "0", .doc = "its noise rms [V]")                    \
  X(K_S_STAR_GAIN_ERROR, .parent = K_SENSORS, .key = "star_gain_error", .type = SK_NUM,            \
    RANGE(-0.49, 0.49), AT(F64, plant.sensors.star_gain_error), .dflt = "0",                       \
    .doc = "its gain error [relative]")                                                            \
  X(K_S_STAR_OFFSET, .parent = K_SENSORS, .key = "star_offset", .type = SK_NUM, RANGE(-1e3, 1e3),  \
    AT(F64, plant.sensors.star_offset), .dflt = "0", .doc = "its offset [V]")                      \
  X(K_S_STAR_TAU, .parent = K_SENSORS, .key = "star_tau", .type = SK_NUM, RANGE(0.0, 1e-4),        \
    AT(F64, plant.sensors.star_tau), .dflt = "0",                                                  \
    .doc = "its circuit's time constant [s]; at most (dfc_t_meas - dead_time)/5")                  \
  X(K_S_GAIN_ERROR, .parent = K_SENSORS, .key = "gain_error", .type = SK_ARRAY3,                   \
    RANGE(-1e3, 1e3), AT(F64X3, plant.sensors.gain_error), .dflt = "0",                            \
    .doc = "current gain error per phase [relative]")                                              \
  X(K_S_OFFSET_ERROR, .parent = K_SENSORS, .key = "offset_error", .type = SK_ARRAY3,               \
    RANGE(-1e3, 1e3), AT(F64X3, plant.sensors.offset_error), .dflt = "0",                          \
    .doc = "current offset per phase [A]")                                                         \
  /* ---- controller: the drive's parameters (docs/parameters.md) ---- */                          \
  X(K_CONTROLLER, .parent = K_ROOT, .key = "controller", .type = SK_OBJECT, .params = 1,           \
    .set = controller_params,                                                                      \
    .doc = "the drive's parameters (`docs/parameters.md`)")                \
  X(K_C_MAP, .parent = K_CONTROLLER, .key = "map", .type = SK_STRING, .set = controller_map,       \
    .dflt = "the machine's", .doc = "the drive's own flux map (a commissioned one), the plant keeping machine.map") \
  X(K_C_ESTIMATES, .parent = K_CONTROLLER, .key = "estimates", .type = SK_OBJECT,                  \
    .post = estimates_post, .doc = "detuning: the controller's machine as factors of the plant's") \
  X(K_C_E_RS, .parent = K_C_ESTIMATES, .key = "rs_scale", .type = SK_NUM, RANGE(0.1, 10.0),        \
    AT_CTX(F64, est[0]), DEF(1.0), .doc = "R_s")                                                   \
  X(K_C_E_LS, .parent = K_C_ESTIMATES, .key = "ls_scale", .type = SK_NUM, RANGE(0.1, 10.0),        \
    AT_CTX(F64, est[1]), DEF(1.0), .doc = "L_d and L_q")                                           \
  X(K_C_E_LD, .parent = K_C_ESTIMATES, .key = "ld_scale", .type = SK_NUM, RANGE(0.1, 10.0),        \
    AT_CTX(F64, est[2]), DEF(1.0), .doc = "L_d")                                                   \
  X(K_C_E_LQ, .parent = K_C_ESTIMATES, .key = "lq_scale", .type = SK_NUM, RANGE(0.1, 10.0),        \
    AT_CTX(F64, est[3]), DEF(1.0), .doc = "L_q")                                                   \
  X(K_C_E_LAMBDA_M, .parent = K_C_ESTIMATES, .key = "lambda_m_scale", .type = SK_NUM,              \
    RANGE(0.1, 10.0), AT_CTX(F64, est[4]), DEF(1.0), .doc = "lambda_m")                            \
  /* ---- references ---- */                                                                       \
  X(K_REFERENCES, .parent = K_ROOT, .key = "references", .type = SK_OBJECT,                        \
    .doc = "commands over time (not with --can)")                                                  \
  X(K_R_ENABLE_AT, .parent = K_REFERENCES, .key = "enable_at", .type = SK_NUM, RANGE(0.0, 1e6),    \
    AT(F64, enable_at), .dflt = "0", .doc = "enable command time [s]")                             \
  X(K_R_DISABLE_AT, .parent = K_REFERENCES, .key = "disable_at", .type = SK_NUM, RANGE(0.0, 1e6),  \
    AT(F64, disable_at), .dflt = "none", .doc = "disable time [s] (none unless > enable_at)")      \
  X(K_R_TORQUE, .parent = K_REFERENCES, .key = "torque", AT(PROFILE, ref.torque),                  \
    SK_PROFILE_DOC("torque reference [N m]"))                                                      \
  X(K_R_SPEED, .parent = K_REFERENCES, .key = "speed", AT(PROFILE, ref.speed),                     \
    SK_PROFILE_DOC("speed reference, mechanical [rad/s]"))                                         \
  X(K_R_ID, .parent = K_REFERENCES, .key = "id", AT(PROFILE, ref.id),                              \
    SK_PROFILE_DOC("d current reference [A] (current mode)"))                                      \
  X(K_R_IQ, .parent = K_REFERENCES, .key = "iq", AT(PROFILE, ref.iq),                              \
    SK_PROFILE_DOC("q current reference [A] (current mode)"))                                      \
  X(K_R_FLUX, .parent = K_REFERENCES, .key = "flux", AT(PROFILE, ref.flux),                        \
    SK_PROFILE_DOC("flux reference [Vs], 0 = automatic"))                                          \
  /* ---- commission ---- */                                                                       \
  X(K_COMMISSION, .parent = K_ROOT, .key = "commission", .type = SK_OBJECTS,                        \
    .max = SIL_COMMISSION_MAX, .stride = sizeof(int), .set = commission_pre, .post = commission_post, \
    .doc = "identification procedures run in turn, drive disabled, before the enable (docs/commissioning.md)") \
  X(K_CM_PROC, .parent = K_COMMISSION, .key = "proc", .type = SK_ENUM, .name_of = sil_proc_name,   \
    .req = "an identification procedure", .set = commission_proc, AT(INT, commission.proc[0]),     \
    .doc = "the procedure (proc.h: a row with PROC_CAP_IDENT)")                                   \
  /* ---- inject ---- */                                                                           \
  X(K_INJECT, .parent = K_ROOT, .key = "inject", .type = SK_OBJECT, .post = inject_post,           \
    .doc = "injected failures")                                                                    \
  X(K_I_TRIP_AT, .parent = K_INJECT, .key = "trip_at", .type = SK_NUM, RANGE(0.0, 1e6),            \
    AT(F64, trip_at), .dflt = "none", .doc = "the main loop posts trip_cause once, at this time [s]")\
  X(K_I_TRIP_CAUSE, .parent = K_INJECT, .key = "trip_cause", .type = SK_ENUM,                      \
    .names = fault_names, AT_CTX(INT, cause), .dflt = "none",                                      \
    .doc = "a fault of DRIVE_FAULT_LIST (with trip_at)")                                           \
  X(K_I_ENCODER_ERROR, .parent = K_INJECT, .key = "encoder_error", AT(PROFILE, encoder_error),     \
    SK_PROFILE_DOC("added to the encoder reading [rad mech]"))                                     \
  X(K_I_ENCODER_INVALID, .parent = K_INJECT, .key = "encoder_invalid",                             \
    AT(PROFILE, encoder_invalid), SK_PROFILE_DOC("> 0.5: the encoder reports an error"))           \
  X(K_I_MAIN_STALL, .parent = K_INJECT, .key = "main_stall", AT(PROFILE, main_stall),              \
    SK_PROFILE_DOC("> 0.5: the main loop does not run"))                                           \
  X(K_I_ISR_STALL, .parent = K_INJECT, .key = "isr_stall", AT(PROFILE, isr_stall),                 \
    SK_PROFILE_DOC("> 0.5: the PWM-period interrupt does not run"))                                \
  X(K_I_ISR_OVERRUN, .parent = K_INJECT, .key = "isr_overrun", AT(PROFILE, isr_overrun),           \
    SK_PROFILE_DOC("> 0.5: the interrupt ends after the next valley"))                             \
  X(K_I_CM_SCALE_D, .parent = K_INJECT, .key = "cm_scale_d", AT(PROFILE, cm_scale_d),              \
    SK_PROFILE_DOC("the LIVE parameter cm_scale_d over time"))                                     \
  X(K_I_CM_SCALE_Q, .parent = K_INJECT, .key = "cm_scale_q", AT(PROFILE, cm_scale_q),              \
    SK_PROFILE_DOC("the LIVE parameter cm_scale_q over time"))                                     \
  X(K_I_RS_SCALE, .parent = K_INJECT, .key = "rs_scale", .type = SK_BOUNDED,                       \
    RANGE(0.0, PLANT_RS_SCALE_MAX), .lo_open = 1, AT(PROFILE, plant.faults.rs_scale),              \
    .dflt = "1", .plant_field = "faults.rs_scale", .doc = "the plant's R_s times this")           \
  X(K_I_LAMBDA_M_SCALE, .parent = K_INJECT, .key = "lambda_m_scale", .type = SK_BOUNDED,           \
    RANGE(0.0, PLANT_LAMBDA_M_SCALE_MAX), AT(PROFILE, plant.faults.lambda_m_scale), .dflt = "1",   \
    .plant_field = "faults.lambda_m_scale", .doc = "the plant's PM flux times this (linear)")      \
  X(K_I_C_SCALE, .parent = K_INJECT, .key = "c_scale", .type = SK_BOUNDED,                         \
    RANGE(0.0, PLANT_C_SCALE_MAX), .lo_open = 1, AT(PROFILE, plant.faults.c_scale), .dflt = "1",   \
    .plant_field = "faults.c_scale", .doc = "the link capacitance times this (not ideal)")        \
  X(K_I_STAR_SHIFT, .parent = K_INJECT, .key = "star_shift", .type = SK_BOUNDED,                   \
    RANGE(-PLANT_STAR_SHIFT_MAX, PLANT_STAR_SHIFT_MAX), AT(PROFILE, plant.faults.star_shift),      \
    .dflt = "0", .plant_field = "faults.star_shift",                                               \
    .doc = "the star point's saliency axis turned [rad el.]")                                      \
  X(K_I_GATE_DRIVER, .parent = K_INJECT, .key = "gate_driver", AT(PROFILE, gate_driver),           \
    SK_PROFILE_DOC("> 0.5: the gate driver's nFAULT asserted"))                                    \
  POWER_FAULT(X, K_I_SWITCH_OPEN, "switch_open", "switch", switch_names, SWITCH_HINT,              \
              "a switch that never conducts (switching model)")                                    \
  POWER_FAULT(X, K_I_SWITCH_CLOSED, "switch_closed", "switch", switch_names, SWITCH_HINT,          \
              "a switch that always conducts (switching model)")                                   \
  POWER_FAULT(X, K_I_PHASE_LOST, "phase_lost", "phase", phase_names, PHASE_HINT,                   \
              "a leg's gate signals lost (switching model)")                                       \
  POWER_FAULT(X, K_I_PHASE_OPEN, "phase_open", "phase", phase_names, PHASE_HINT,                   \
              "a motor lead disconnected (switching model)")                                       \
  POWER_FAULT(X, K_I_PHASE_SHORT, "phase_short", "phases", pair_names, PAIR_HINT,                  \
              "two motor leads shorted (switching model)")                                         \
  POWER_FAULT(X, K_I_GROUND_SHORT, "ground_short", "phase", phase_names, PHASE_HINT,               \
              "a motor lead shorted to the negative rail (switching model)")                       \
  X(K_I_CURRENT, .parent = K_INJECT, .key = "current", .type = SK_OBJECTS,                         \
    .max = SIL_ADC_FAULTS_MAX, .stride = sizeof(sil_adc_fault_t), .set = current_pre,              \
    .post = current_post, .doc = "channel faults")                                     \
  X(K_I_CUR_CHANNEL, .parent = K_I_CURRENT, .key = "channel", .type = SK_ENUM,                     \
    .names = phase_names, .req = "a, b or c", AT(INT, current_faults.f[0].channel),                \
    .doc = "the channel")                                                                          \
  X(K_I_CUR_KIND, .parent = K_I_CURRENT, .key = "kind", .type = SK_ENUM,                           \
    .name_of = sil_adc_kind_name, .req = "stuck, frozen, nan, invalid, offset or gain",            \
    AT(INT, current_faults.f[0].kind), .doc = "what the channel reads")                           \
  X(K_I_CUR_ACTIVE, .parent = K_I_CURRENT, .key = "active", .type = SK_PROFILE,                    \
    AT(PROFILE, current_faults.f[0].active), .dflt = "always", .doc = "acts while > 0.5")          \
  X(K_I_CUR_VALUE, .parent = K_I_CURRENT, .key = "value", .type = SK_BOUNDED, .by_hook = 1,        \
    AT(PROFILE, current_faults.f[0].value), .dflt = "none",                                        \
    .doc = "stuck, offset: [A] within +-i_full_scale; gain: in [-1, 9]; others: none")             \
  X(K_I_ENCODER, .parent = K_INJECT, .key = "encoder", .type = SK_OBJECT, .post = encoder_post,    \
    .doc = "the encoder's faults (sil_enc_faults.h)")                                              \
  X(K_I_ENC_FROZEN, .parent = K_I_ENCODER, .key = "frozen", AT(PROFILE, encoder_faults.frozen),    \
    SK_PROFILE_DOC("> 0.5: the reading holds"))                                                    \
  X(K_I_ENC_REVERSED, .parent = K_I_ENCODER, .key = "reversed",                                    \
    AT(PROFILE, encoder_faults.reversed), SK_PROFILE_DOC("> 0.5: it counts backwards"))            \
  X(K_I_ENC_JITTER, .parent = K_I_ENCODER, .key = "jitter", .type = SK_NUM, RANGE(0.0, 1e-3),      \
    AT(F64, encoder_faults.jitter), .dflt = "0", .doc = "rms sample-time jitter [s]")              \
  X(K_I_ENC_MISSING, .parent = K_I_ENCODER, .key = "missing", .type = SK_NUM, RANGE(0.0, 0.5),     \
    AT(F64, encoder_faults.missing), .dflt = "0",                                                  \
    .doc = "probability that a count edge is lost (needs sensors.encoder_cpr > 0)")                \
  X(K_I_ENC_SEED, .parent = K_I_ENCODER, .key = "seed", .type = SK_INT, RANGE(0.0, 2147483647.0),  \
    AT(U32, encoder_faults.seed), DEF(1.0), .doc = "seed of the jitter and missing draws")         \
  X(K_I_CAN, .parent = K_INJECT, .key = "can", .type = SK_OBJECT, .post = can_post,                \
    .doc = "CAN frame loss and delay (--can socketcand:PORT)")                                     \
  X(K_I_CAN_SEED, .parent = K_I_CAN, .key = "seed", .type = SK_INT, RANGE(0.0, 2147483647.0),      \
    AT(U32, can_faults.seed), DEF(1.0), .doc = "seed of the loss and jitter draws")                \
  CAN_DIR(X, K_I_CAN_RX, "rx", can_faults.rx, "host -> drive")                                     \
  CAN_DIR(X, K_I_CAN_TX, "tx", can_faults.tx, "drive -> host")                                     \
  X(K_I_PASSIVE_LOAD, .parent = K_INJECT, .key = "passive_load", .type = SK_OBJECT,                \
    .post = passive_load_post, .doc = "a friction load that never drives the rotor (free mode)")   \
  X(K_I_PL_COULOMB, .parent = K_I_PASSIVE_LOAD, .key = "coulomb", .type = SK_BOUNDED,              \
    RANGE(0.0, 1e6), AT(PROFILE, plant.faults.coulomb), .dflt = "0",                               \
    .plant_field = "faults.coulomb", .doc = "Coulomb friction [N m]")                              \
  X(K_I_PL_VISCOUS, .parent = K_I_PASSIVE_LOAD, .key = "viscous", .type = SK_BOUNDED,              \
    RANGE(0.0, 1e6), AT(PROFILE, plant.faults.viscous), .dflt = "0",                               \
    .plant_field = "faults.viscous", .doc = "viscous friction [N m s/rad], added to mechanics.b")  \
  /* ---- log, board ---- */                                                                       \
  X(K_LOG, .parent = K_ROOT, .key = "log", .type = SK_OBJECT, .doc = "the log (.npy)")             \
  X(K_LOG_DECIMATION, .parent = K_LOG, .key = "decimation", .type = SK_INT, RANGE(1.0, 1e6),       \
    AT(INT, log_decimation), DEF(16.0), .doc = "log every n-th period")                            \
  X(K_BOARD, .parent = K_ROOT, .key = "board", .type = SK_OBJECT, .set = board_pre,                \
    .doc = "the board the SIL HAL models")                                                         \
  X(K_B_PRESET, .parent = K_BOARD, .key = "preset", .type = SK_STRING, .by_hook = 1,               \
    .dflt = DEFAULT_BOARD, .doc = "a board preset (sil/runner/board_presets.c)")                   \
  X(K_B_DUTY_MIN, .parent = K_BOARD, .key = "duty_min", .type = SK_NUM, RANGE(0.0, 0.5),           \
    AT(F32, board.duty_min), .dflt = "preset", .doc = "the duty range's low end")                  \
  X(K_B_DUTY_MAX, .parent = K_BOARD, .key = "duty_max", .type = SK_NUM, RANGE(0.5, 1.0),           \
    AT(F32, board.duty_max), .dflt = "preset", .doc = "its high end")                              \
  X(K_B_TIMER_COUNTS, .parent = K_BOARD, .key = "timer_counts", .type = SK_INT, RANGE(0.0, 1e6),   \
    AT(U32, board.timer_counts), .dflt = "preset", .doc = "compare steps per period, 0 = exact")   \
  X(K_B_WATCHDOG_MS, .parent = K_BOARD, .key = "watchdog_ms", .type = SK_INT,                      \
    RANGE(0.0, 60000.0), AT(U32, board.watchdog_ms), .dflt = "preset",                             \
    .doc = "watchdog timeout [ms], 0 = none")                                                      \
  X(K_B_ASYM_EDGES, .parent = K_BOARD, .key = "asym_edges", .type = SK_INT, RANGE(0.0, 1.0),       \
    AT(BOOL, board.asym_edges), .dflt = "preset",                                                  \
    .doc = "1: each leg's edges placed independently (star-point sources)")
/* clang-format on */

#define SWITCH_HINT "a_low, a_high, b_low, b_high, c_low or c_high"
#define PHASE_HINT  "a, b or c"
#define PAIR_HINT   "ab, bc or ca"

#endif
