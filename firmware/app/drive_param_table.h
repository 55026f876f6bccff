/*
 * drive_param_table.h - THE parameter table of the drive: one row per
 * parameter, the single source of
 *   - the struct drive_config_t and its defaults   (drive_config.h/.c)
 *   - the range check of every field                (drive_config.c)
 *   - access by id for CAN                          (drive_params.c)
 *   - the ISR stream's configuration words          (sil/runner/isr_stream.h)
 *   - the scenario keys and their ranges            (sil/runner/scenario.c)
 *   - the DBC value table of reply_param, the Python tools' table and the
 *     docs table: generated from `fluxdrive-sil --print-params` by
 *     `fluxdrive params --write` (tools/src/fluxdrive/params.py); the CTest
 *     test params/agreement fails when they differ from this file.
 * Relations between fields (i_trip >= i_max, ...) are drive_config_check's
 * (drive_config.c), each reported under the field it names.
 *
 * Columns: X(id, name, type, unit, default, min, max, access, scenario, doc)
 *   id        CAN parameter number (PARAM_REQ.param_id), unique, 1..63 or
 *             96..255 (64..95 are the CAN protocol's own, can_proto.h)
 *   type      F32 float | U16 uint16_t | U32 uint32_t | LAW drive_law_t |
 *             MODE drive_mode_t | POS pos_source_t (enums: min 0, max count-1) |
 *             MAP a flux-map blob (const uint32_t *, docs/flux-maps.md): read as
 *             the low 24 bits of its CRC-32 (what a float carries exactly),
 *             set by the scenario (or a board's linked table), never by a number
 *   access    RO read only | IDLE written with the gates off | LIVE also
 *             while running (applied by the ISR at its next period)
 *   scenario  the scenario key that sets it ("section.key"); keys outside
 *             "controller" are converted by their section (docs/scenarios.md)
 * Adding a parameter: one row here, then use cfg->name where it acts, and
 * run `fluxdrive params --write` (docs/architecture.md, walk-through).
 */
#ifndef FLUXDRIVE_DRIVE_PARAM_TABLE_H
#define FLUXDRIVE_DRIVE_PARAM_TABLE_H

/* clang-format off */
#define DRIVE_PARAM_TABLE(X)                                                                                 \
  /* machine: the controller's estimates (may differ from the plant) */                                  \
  X(1,  pole_pairs,     F32,  "",       21.0f,       1.0f,    100.0f,   IDLE, "machine.pole_pairs",        \
    "pole pairs (an integer)")                                                                              \
  X(2,  rs,             F32,  "Ohm",    7.1f,        1e-5f,   1e3f,     IDLE, "machine.rs",                \
    "stator phase resistance")                                                                              \
  X(3,  ld,             F32,  "H",      0.057f,      1e-7f,   10.0f,    IDLE, "machine.ld",                \
    "d-axis inductance (d on the PM flux)")                                                                 \
  X(4,  lq,             F32,  "H",      0.057f,      1e-7f,   10.0f,    IDLE, "machine.lq",                \
    "q-axis inductance")                                                                                    \
  X(5,  lambda_m,       F32,  "Vs",     0.19f,       0.0f,    10.0f,    IDLE, "machine.lambda_m",          \
    "PM flux linkage, peak per phase (0: reluctance machine)")                                              \
  X(7,  machine_map,    MAP,  "",       0.0f,        0.0f,    16777215.0f, RO, "machine.map",             \
    "flux map of a saturated machine: its blob's CRC-32, low 24 bits (0: linear, ld, lq, lambda_m)")      \
  X(6,  inertia,        F32,  "kg m^2", 0.021f,      1e-9f,   1e3f,     IDLE, "mechanics.j",               \
    "inertia, for the speed-loop design")                                                                   \
  /* limits and protections */                                                                              \
  X(10, i_max,          F32,  "A",      3.5355339f,  1e-3f,   1e4f,     IDLE, "controller.i_max",          \
    "current amplitude limit (peak)")                                                                       \
  X(11, torque_max,     F32,  "N m",    20.0f,       0.0f,    1e5f,     LIVE, "controller.torque_max",     \
    "torque reference limit")                                                                               \
  X(12, speed_max,      F32,  "rad/s",  125.66371f,  0.0f,    1e5f,     LIVE, "controller.speed_max",      \
    "speed reference limit, mechanical")                                                                    \
  X(13, v_margin,       F32,  "",       0.95f,       0.1f,    1.0f,     IDLE, "controller.v_margin",       \
    "usable fraction of the modulator's linear voltage range")                                              \
  X(14, i_trip,         F32,  "A",      7.0710678f,  1e-3f,   1e4f,     LIVE, "controller.i_trip",         \
    "phase current trip (any sample)")                                                                      \
  X(15, v_dc_max,       F32,  "V",      400.0f,      1.0f,    1e4f,     LIVE, "controller.v_dc_max",       \
    "DC-link overvoltage trip")                                                                             \
  X(16, v_dc_min,       F32,  "V",      150.0f,      0.0f,    1e4f,     LIVE, "controller.v_dc_min",       \
    "DC-link undervoltage trip while the gates are on")                                                     \
  X(17, speed_trip,     F32,  "rad/s",  157.07964f,  1e-3f,   1e5f,     LIVE, "controller.speed_trip",     \
    "overspeed trip, mechanical")                                                                           \
  X(18, offset_max,     F32,  "A",      0.5f,        0.0f,    1e3f,     LIVE, "controller.offset_max",     \
    "largest acceptable current-sensor offset")                                                             \
  X(19, delta_max,      F32,  "rad",    1.3962634f,  0.1f,    1.5f,     IDLE, "controller.delta_max",      \
    "load-angle (MTPV) limit of the DFVC laws")                                                             \
  X(20, vsd_max,        F32,  "V",      60.0f,       0.0f,    1e4f,     IDLE, "controller.vsd_max",        \
    "flux-axis voltage limit v_sd,max of the DFVC laws")                                                    \
  X(21, flux_min,       F32,  "Vs",     0.038f,      0.0f,    10.0f,    IDLE, "controller.flux_min",       \
    "minimum flux reference of the DFVC laws")                                                              \
  X(22, lc_time,        F32,  "s",      0.002f,      1e-4f,   1.0f,     LIVE, "controller.lc_time",        \
    "loss of control: time the current or load-angle condition may persist before the trip")               \
  X(23, lc_current,     F32,  "",       1.15f,       1.0f,    3.0f,     LIVE, "controller.lc_current",     \
    "loss of control: current amplitude above lc_current * i_max")                                          \
  X(24, lc_delta,       F32,  "rad",    0.17453293f, 0.0f,    1.5f,     LIVE, "controller.lc_delta",       \
    "loss of control: load angle beyond delta_max + lc_delta (DFVC laws)")                                  \
  X(25, lc_track,       F32,  "",       0.5f,        0.05f,   10.0f,    LIVE, "controller.lc_track",       \
    "loss of control: torque, flux or observer error above lc_track times its scale")                      \
  X(109, i_sum_rel,     F32,  "",       0.2f,        0.01f,   1.0f,     LIVE, "controller.i_sum_rel",      \
    "current-sensor check: |i_a + i_b + i_c| above i_sum_rel times the largest |i_x| (and i_sum_abs) trips current_sensor") \
  X(110, i_sum_abs,     F32,  "A",      0.05f,       0.0f,    1e3f,     LIVE, "controller.i_sum_abs",      \
    "current-sensor check: the noise floor of |i_a + i_b + i_c| (raised to 3 sigma of the sum's noise the offset calibration measures plus 1.5 ADC steps)")                                          \
  X(120, asc_speed,     F32,  "",       0.9f,        0.0f,    2.0f,     LIVE, "controller.asc_speed",      \
    "safe state: active short circuit above asc_speed times the rectifier speed v_dc/(sqrt(3) psi_pm), or on overvoltage; 0: gates off only (docs/faults.md)") \
  X(121, asc_hold,      F32,  "s",      0.05f,       1e-3f,   10.0f,    LIVE, "controller.asc_hold",       \
    "safe state: shortest active short circuit (its current transient decays before the speed is judged from the current vector)") \
  X(122, pos_emf_tol,   F32,  "",       0.5f,        0.0f,    10.0f,    LIVE, "controller.pos_emf_tol",    \
    "position plausibility (encoder): trips position when the voltage applied over the check's window differs from the model's flux change at the source's angle (+ R i) by more than pos_emf_tol (each flux part's change + R i) + 5 % v_dc; 0: off") \
  X(130, overrun_n,     U16,  "",       16.0f,       1.0f,    32.0f,    LIVE, "controller.overrun_n",      \
    "ISR overrun check: window of slow periods (main-loop periods, slow_div ISRs each)")                  \
  X(131, overrun_k,     U16,  "",       4.0f,        1.0f,    32.0f,    LIVE, "controller.overrun_k",      \
    "ISR overrun check: overruns in overrun_k of the last overrun_n slow periods trip overrun")            \
  X(26, lc_track_time,  F32,  "s",      0.02f,       1e-4f,   1.0f,     LIVE, "controller.lc_track_time",  \
    "loss of control: time a tracking condition may persist (a reversal at the voltage limit takes ms)")   \
  /* controller */                                                                                          \
  X(30, current_bw,     F32,  "rad/s",  2000.0f,     1.0f,    1e5f,     IDLE, "controller.current_bw",     \
    "FOC current-loop bandwidth")                                                                           \
  X(31, speed_bw,       F32,  "rad/s",  60.0f,       0.1f,    1e5f,     LIVE, "controller.speed_bw",       \
    "speed-loop bandwidth")                                                                                 \
  X(32, accel_max,      F32,  "rad/s^2", 125.66371f, 1e-3f,   1e7f,     LIVE, "controller.accel_max",      \
    "speed reference slew limit, mechanical")                                                               \
  X(33, pll_bw,         F32,  "rad/s",  400.0f,      1.0f,    1e5f,     IDLE, "controller.pll_bw",         \
    "position-source PLL bandwidth")                                                                        \
  X(34, flux_obs_wc,    F32,  "rad/s",  125.0f,      0.0f,    1e5f,     IDLE, "controller.flux_obs_wc",    \
    "hybrid flux observer crossover omega_c (Rubino 2020)")                                                 \
  X(35, dfvc_flux_bw,   F32,  "rad/s",  6283.1853f,  1.0f,    1e5f,     IDLE, "controller.dfvc_flux_bw",   \
    "PI-DFVC flux-loop bandwidth")                                                                          \
  X(36, dfvc_iqs_bw,    F32,  "rad/s",  6283.1853f,  1.0f,    1e5f,     IDLE, "controller.dfvc_iqs_bw",    \
    "PI-DFVC i_qs-loop bandwidth")                                                                          \
  X(52, dfvc_decoupled_bw,    F32,  "rad/s",  628.31853f,  1.0f,    1e5f,     IDLE, "controller.dfvc_decoupled_bw",    \
    "decoupled DFVC: bandwidth Omega of both loops, k_p = 2 Omega, k_i = Omega^2 (Varatharajan 2022 (28))") \
  X(53, dfvc_decoupled_gains, U16,  "",       0.0f,        0.0f,    2.0f,     IDLE, "controller.dfvc_decoupled_gains", \
    "decoupled DFVC gain set: 0 proposed (a, b) (22), 1 state of the art (a', b') (17), 2 constant-gain PI (26)") \
  X(54, dfvc_decoupled_refs,  U16,  "",       1.0f,        0.0f,    1.0f,     IDLE, "controller.dfvc_decoupled_refs",  \
    "decoupled DFVC references: 0 the flux map's MTPA/MTPV tables (29)-(31), 1 online (32), (34)")       \
  X(55, sat_obs_g,      F32,  "rad/s",  31.415927f,  0.0f,    1e5f,     IDLE, "controller.sat_obs_g",      \
    "decoupled DFVC: hybrid flux observer gain g (Varatharajan 2022 (24))")                                \
  X(56, k_a,            F32,  "1/(A s)", 60.0f,      0.0f,    1e4f,     IDLE, "controller.k_a",            \
    "decoupled DFVC: online MTPA adaptation gain (32)")                                                    \
  X(57, k_t,            F32,  "",       0.9f,        0.1f,    1.0f,     IDLE, "controller.k_t",            \
    "decoupled DFVC: torque margin from the MTPV limit (31), (34)")                                        \
  X(58, k_v,            F32,  "",       0.9f,        0.1f,    1.0f,     IDLE, "controller.k_v",            \
    "decoupled DFVC: voltage margin of the maximum flux (30)")                                             \
  X(59, cm_scale_d,     F32,  "",       1.0f,        0.1f,    10.0f,    LIVE, "controller.cm_scale_d",     \
    "decoupled DFVC: factor on the controller's map lambda_d (current-model error; 1 = the map)")         \
  X(60, cm_scale_q,     F32,  "",       1.0f,        0.1f,    10.0f,    LIVE, "controller.cm_scale_q",     \
    "decoupled DFVC: factor on the controller's map lambda_q (current-model error; 1 = the map)")         \
  X(37, enc_offset,     F32,  "rad",    0.0f,        -7.0f,   7.0f,     IDLE, "controller.enc_offset",     \
    "electrical angle at encoder zero (found by the alignment when align_time > 0)")                        \
  X(38, pos_source,     POS,  "",       0.0f,        0.0f,    0.0f,     IDLE, "controller.pos_source",     \
    "position source")                                                                                      \
  X(39, enc_cpr,        U32,  "",       4096.0f,     0.0f,    16777216.0f, IDLE, "sensors.encoder_cpr",    \
    "encoder counts per mechanical revolution (0: not quantised)")                                          \
  X(44, align_time,     F32,  "s",      0.0f,        0.0f,    10.0f,    IDLE, "controller.align_time",     \
    "alignment before run: d current along the assumed axis for this long (0: no alignment, else >= ts)")               \
  X(45, align_current,  F32,  "A",      1.0f,        0.0f,    1e4f,     IDLE, "controller.align_current",  \
    "d current of the alignment")                                                                           \
  X(208, id_fmap_current, F32, "A",     3.5f,        0.0f,    1e4f,     IDLE, "controller.id_fmap_current", \
    "flux maps (procedure fmap): the grid's current range, |i| <= this (clamped to i_max)")               \
  X(209, id_fmap_nd,    U16,  "",       9.0f,        2.0f,    64.0f,    IDLE, "controller.id_fmap_nd",     \
    "flux maps: grid points along i_d (-range .. range); id_fmap_nd x id_fmap_nq <= 254")                   \
  X(210, id_fmap_nq,    U16,  "",       5.0f,        2.0f,    64.0f,    IDLE, "controller.id_fmap_nq",     \
    "flux maps: grid points along i_q (0 .. range; i_q bipolar)")                                          \
  X(211, id_fmap_dwell, F32,  "s",      0.003f,      1e-4f,   1.0f,     IDLE, "controller.id_fmap_dwell",  \
    "flux maps: dwell at each current level (the point, zero)")                                           \
  /* identification with an encoder (issue 25 d-g; proc_poles.c, proc_enc.c, proc_flux.c, proc_mech.c) */ \
  X(212, id_i_test,     F32,  "A",      0.0f,        0.0f,    1e4f,     IDLE, "controller.id_i_test",      \
    "identification: test current amplitude (poles, enc: the turned vector; flux: the d current; mech: the q current of the torque steps); clamped to i_max; 0: 0.3 i_max") \
  X(213, id_speed,      F32,  "rad/s",  0.0f,        0.0f,    1e5f,     IDLE, "controller.id_speed",       \
    "identification: speed of the PM flux measurement (flux), mechanical; 0: 0.2 speed_max; at most id_speed_max") \
  X(214, id_speed_max,  F32,  "rad/s",  0.0f,        0.0f,    1e5f,     IDLE, "controller.id_speed_max",   \
    "identification: speed bound of the spinning procedures (flux, mech), mechanical: mech accelerates to 0.8 of it, either trips overspeed above 1.2 of it; 0: 0.3 speed_max") \
  X(61, start_mode,     U16,  "",       0.0f,        0.0f,    1.0f,     IDLE, "controller.start_mode",     \
    "start of a position source: 0 align (d current along theta = 0 for align_time, the rotor turns), 1 hold (star point: angle at standstill, polarity from d-axis saturation pulses, no free rotor)") \
  X(46, pos_err_max,    F32,  "rad",    0.5f,        0.01f,   3.2f,     LIVE, "controller.pos_err_max",    \
    "position fault: measured angle this far (electrical) from the PLL's prediction")                       \
  /* Direct Flux Control position (Fabbri 2022; docs/dfc.md) */                                            \
  X(8,  dfc_a,          F32,  "",       0.05f,       -1.0f,   1.0f,     IDLE, "controller.dfc_a",          \
    "DFC: amplitude a of the 2theta term of Gamma / v_dc (3.6)-(3.7)")                                     \
  X(9,  dfc_b,          F32,  "",       -0.0047f,    -1.0f,   1.0f,     LIVE, "controller.dfc_b",          \
    "DFC: amplitude b of the 4theta term of Gamma / v_dc (3.6)-(3.7); IVD needs |b/a| < 1/2, the EKF <= 0.35") \
  X(27, dfc_iter,       U16,  "",       1.0f,        0.0f,    8.0f,     LIVE, "controller.dfc_iter",       \
    "IVD: iterations of (3.76) / (3.100)")                                                                  \
  X(28, dfc_phi_a,      F32,  "rad/A",  0.0f,        -1.0f,   1.0f,     LIVE, "controller.dfc_phi_a",      \
    "Full IVD: phase shift phi_a of the 2theta term per A of i_q (3.97); |phi_a| i_max <= 0.1 rad")                                  \
  X(29, dfc_phi_b,      F32,  "rad/A",  0.0f,        -1.0f,   1.0f,     LIVE, "controller.dfc_phi_b",      \
    "Full IVD: phase shift phi_b of the 4theta term per A of i_q (3.97); |phi_b| i_max <= 0.2 rad")                                  \
  X(47, dfc_t0,         F32,  "s",      1.5e-6f,     2e-7f,   2e-5f,    IDLE, "controller.dfc_t0",         \
    "DFC window: test vector start after the period start (the star point is sampled at t0/2 before it)") \
  X(48, dfc_tw,         F32,  "s",      3e-6f,       5e-7f,   3e-5f,    IDLE, "controller.dfc_tw",         \
    "DFC window: test vector length")                                                                       \
  X(49, dfc_t_meas,     F32,  "s",      2.5e-6f,     1e-7f,   3e-5f,    IDLE, "controller.dfc_t_meas",     \
    "DFC window: star-point sample after the test-vector edge (dead time plus settling: > dead_time, < dfc_tw)")        \
  /* Kalman filter, EKF and RLS on the star-point position (Fabbri 2022 ch. 4; docs/dfc.md) */         \
  X(96, friction,       F32,  "N m s/rad", 0.0f,     0.0f,    1e4f,     IDLE, "mechanics.b",               \
    "viscous friction B, for the Kalman filter's model (4.46)")                                            \
  /* kf_q_omega, kf_q_load, dfc_sigma: ranges found on the star-point presets (fabbri2022_t51,     \
   * _fig33, _ebike; dfc+kf, ivd+kf, ekf, ivd+kf+rls; start, 500 / 50 rpm, load step; docs/faults.md):\
   * Q_11 100 (rad/s)^2: overspeed at 0.58 s (dfc+kf, ebike), 1e3: 18 ms after the start (fig33,     \
   * ebike), the filter follows the noise; Q_33 0.1 (N m)^2: overspeed at 0.19 s (ekf, fig33), 1:    \
   * 23 ms (t51); sigma_v 2e-5: the RLS trips overspeed at 0.38 s (t51), 4e-6: the KF at 21 ms        \
   * (ebike); sigma_v 0.3 (six times the presets' a): position at 0.12 s (ekf). 5e-5 is below a       \
   * 12-bit star channel's step over the link (2.4e-4 / sqrt 12), 0.1 twice the presets' a. */      \
  X(97, kf_q_omega,     F32,  "(rad/s)^2", 1.0f,     0.0f,    10.0f,    LIVE, "controller.kf_q_omega",     \
    "KF/EKF: process noise of the electrical speed, Q_11 (5.1)")                                           \
  X(98, kf_q_theta,     F32,  "rad^2",  0.0f,        0.0f,    10.0f,    LIVE, "controller.kf_q_theta",     \
    "KF/EKF: process noise of the electrical angle, Q_22 (5.1)")                                           \
  X(99, kf_q_load,      F32,  "(N m)^2", 1e-6f,      0.0f,    0.01f,    LIVE, "controller.kf_q_load",      \
    "KF/EKF: process noise of the load torque, Q_33 (5.1)")                                                \
  X(100, dfc_sigma,     F32,  "",       2e-4f,       5e-5f,   0.1f,     LIVE, "controller.dfc_sigma",      \
    "KF/EKF/RLS: standard deviation sigma_v of each DFC signal (Gamma / v_dc) (4.29), (4.38), (4.53)")     \
  X(101, kf_r_scale,    F32,  "",       1.0f,        0.01f,   1e4f,     LIVE, "controller.kf_r_scale",     \
    "KF/EKF: R_k = kf_r_scale times (4.29) / (4.38) (Table 5.2: 1 and 5)")                                  \
  X(102, kf_r_m,        F32,  "1/(rad/s)", 0.0f,     0.0f,    1.0f,     LIVE, "controller.kf_r_m",         \
    "KF/EKF: speed-dependent signal variance, slope m above omega_f (4.42), per sigma_v^2")               \
  X(103, kf_r_wf,       F32,  "rad/s",  0.0f,        0.0f,    1e5f,     LIVE, "controller.kf_r_wf",        \
    "KF/EKF: omega_f of (4.42), electrical")                                                                \
  X(104, kf_r_m2,       F32,  "1/(rad/s)^2", 0.0f,   0.0f,    1.0f,     LIVE, "controller.kf_r_m2",        \
    "KF/EKF: speed-dependent signal variance m_2 omega^2 (4.43), per sigma_v^2")                          \
  X(111, kf_r_sys,      F32,  "",       1.0f,        0.0f,    100.0f,   LIVE, "controller.kf_r_sys",       \
    "KF: the method's own angle error added to R_k, times kf_r_sys: the standard DFC's Delta_0 (3.13), the IVD's bound after dfc_iter iterations (Theorem 1); 0: (4.29) alone, as the thesis's Table 5.2") \
  X(105, rls_lambda,    F32,  "",       0.9999f,     0.9f,    1.0f,     LIVE, "controller.rls_lambda",     \
    "RLS: forgetting factor lambda of the a, b identification (4.55)-(4.57)")                              \
  X(106, rls_p_max,     F32,  "",       1e-5f,       1e-12f,  1.0f,     LIVE, "controller.rls_p_max",      \
    "RLS: upper limit of P's diagonal (and P at the reset): the identification's bandwidth")               \
  X(107, rls_p_min,     F32,  "",       1e-9f,       1e-12f,  1.0f,     LIVE, "controller.rls_p_min",      \
    "RLS: lower limit of P's diagonal (keeps the identification alive)")                                   \
  X(108, rls_w_min,     F32,  "rad/s",  50.0f,       0.0f,    1e5f,     LIVE, "controller.rls_w_min",      \
    "RLS: identify only above this electrical speed (a and b are not separable at standstill)")           \
  /* identification (issue 25; docs/commissioning.md): rs (proc_rs.c), ldq (proc_ldq.c) */                 \
  X(200, id_rs_current, F32,  "A",      0.0f,        0.0f,    1e4f,     IDLE, "controller.id_rs_current",  \
    "rs identification: the current limit (top level 0.9 of it), clamped to i_max; 0: half of i_max")   \
  X(201, id_rs_levels,  U16,  "",       8.0f,        3.0f,    8.0f,     IDLE, "controller.id_rs_levels",   \
    "rs identification: current levels of each sign")                                                     \
  X(202, id_rs_align,   F32,  "s",      0.3f,        0.0f,    10.0f,    IDLE, "controller.id_rs_align",    \
    "rs identification: the alignment at the top level before each sign's levels (the rotor turns)")     \
  X(203, id_rs_settle,  F32,  "s",      0.02f,       0.0f,    10.0f,    IDLE, "controller.id_rs_settle",   \
    "rs identification: a level's settling before its average")                                           \
  X(204, id_rs_avg,     F32,  "s",      0.04f,       1e-3f,   10.0f,    IDLE, "controller.id_rs_avg",      \
    "rs identification: a level's average")                                                               \
  X(205, id_ldq_current, F32, "A",      0.0f,        0.0f,    1e4f,     IDLE, "controller.id_ldq_current", \
    "ldq identification: the d bias current (aligns the rotor, keeps the phase currents' signs); 0: a third of i_max; clamped to i_max / 2") \
  X(206, id_ldq_freq,   F32,  "Hz",     1000.0f,      10.0f,   1e4f,     IDLE, "controller.id_ldq_freq",    \
    "ldq identification: the square-wave injection's frequency (rounded to whole PWM periods)")          \
  X(207, id_ldq_time,   F32,  "s",      0.2f,        0.01f,   10.0f,    IDLE, "controller.id_ldq_time",    \
    "ldq identification: each axis' injection measured for this long")                                     \
  /* identification: the star point's a and b at standstill (proc_star.c, docs/commissioning.md) */     \
  X(240, id_star_current, F32, "",     0.2f,        0.01f,   1.0f,     IDLE, "controller.id_star_current", \
    "star-point a, b identification: the current vector that turns the rotor, per unit of i_max")          \
  X(241, id_star_time,  F32,  "s",      0.4f,        0.05f,   10.0f,    IDLE, "controller.id_star_time",   \
    "star-point a, b identification: each half-turn sweep's time (the alignment before it: half of it)")   \
  /* timing and calibration */                                                                              \
  X(40, ts,             F32,  "s",      6.25e-5f,    1e-6f,   1e-2f,    RO,   "inverter.pwm_frequency",    \
    "PWM and ISR period")                                                                                   \
  X(41, slow_div,       U16,  "",       16.0f,       1.0f,    1000.0f,  RO,   "controller.slow_div",       \
    "speed loop and telemetry every slow_div ISRs")                                                         \
  X(42, dead_time,      F32,  "s",      1e-6f,       0.0f,    1e-4f,    IDLE, "inverter.dead_time",        \
    "inverter dead time, for the compensation")                                                             \
  X(62, r_dev,          F32,  "Ohm",    0.0f,        0.0f,    1.0f,     IDLE, "inverter.r_dev",            \
    "the power stage's device resistance in a phase's path (mean of switch and diode or synchronous rectifier; the board's datasheet), taken out of the rs identification's slope") \
  X(43, offset_samples, U16,  "",       256.0f,      1.0f,    60000.0f, IDLE, "controller.offset_samples", \
    "ISRs averaged by the current-offset calibration")                                                      \
  X(50, law,            LAW,  "",       0.0f,        0.0f,    0.0f,     RO,   "controller.law",            \
    "control law at start-up (CMD_STATE changes the law in force)")                                         \
  X(51, mode,           MODE, "",       0.0f,        0.0f,    0.0f,     RO,   "controller.mode",           \
    "control mode at start-up (CMD_STATE changes the mode in force)")
/* clang-format on */

#endif
