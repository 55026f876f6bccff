/*
 * drive_signal_table.h - THE signal table of the drive: one row per value
 * the drive exposes (its telemetry, drive_telemetry_t, and a few fields of
 * its state), the single source of
 *   - the drive's log columns, their units and docs   (sil/runner/log_npy.c,
 *     docs/log-format.md)
 *   - the CAN telemetry frames' contents              (can_proto.c: every
 *     signal of TM_SPEED .. TM_POSITION and STATUS.state, faults, v_dc that
 *     names a row here is filled from it)
 *   - the DBC comments of those CAN signals and the tools' signal table:
 *     generated from `fluxdrive-sil --print-signals` by
 *     `fluxdrive signals --write` (tools/src/fluxdrive/signals.py); the
 *     CTest test signals/agreement fails when they differ from this file.
 * The laws and the position sources expose their own signals through their
 * rows (ctrl_law_t.signals, pos_source_row_t.signals), the SIL its plant
 * and HAL columns (sil/runner/sil_signal_table.h).
 *
 * Columns: X(name, type, unit, value, can, can_scale, can_unit, doc)
 *   name      the log column
 *   type      F32 | U32 | BOOL (signal_row.h)
 *   value     an expression on s (const drive_signal_src_t *: s->tm the
 *             telemetry the reader holds, s->drv the drive)
 *   can       the CAN signal (can_codec.h, CAN_SIG_<can>) that carries
 *             value * can_scale in can_unit, or NONE
 * Adding a signal: one row here (docs/architecture.md, "Adding a signal"),
 * then `fluxdrive signals --write`.
 */
#ifndef FLUXDRIVE_DRIVE_SIGNAL_TABLE_H
#define FLUXDRIVE_DRIVE_SIGNAL_TABLE_H

#define DRIVE_SIG_RPM 9.54929659f /* rpm per rad/s: 60 / (2 pi) */

/* clang-format off */
#define DRIVE_SIGNAL_TABLE(X)                                                                              \
  X(speed_est,       F32,  "rad/s", s->tm->omega_m,           SPEED_RPM,       DRIVE_SIG_RPM, "rpm",        \
    "speed estimate (position source)")                                                                   \
  X(speed_ref,       F32,  "rad/s", s->tm->speed_ref,         SPEED_REF_RPM,   DRIVE_SIG_RPM, "rpm",        \
    "slew-limited speed reference (speed mode)")                                                          \
  X(torque_ref,      F32,  "N m",   s->tm->torque_ref,        TORQUE_REF,      1.0f, "N m",                 \
    "torque reference in force")                                                                          \
  X(torque_est,      F32,  "N m",   s->tm->torque_est,        TORQUE_EST,      1.0f, "N m",                 \
    "the control law's torque estimate")                                                                  \
  X(i_a_meas,        F32,  "A",     s->tm->i_abc[0],          I_A,             1.0f, "A",                   \
    "measured phase current a after offset removal")                                                      \
  X(i_b_meas,        F32,  "A",     s->tm->i_abc[1],          I_B,             1.0f, "A",                   \
    "measured phase current b after offset removal")                                                      \
  X(i_c_meas,        F32,  "A",     s->tm->i_abc[2],          I_C,             1.0f, "A",                   \
    "measured phase current c after offset removal")                                                      \
  X(i_d_meas,        F32,  "A",     s->tm->i_dq[0],           I_D,             1.0f, "A",                   \
    "measured d current (rotor frame at the angle in use)")                                               \
  X(i_q_meas,        F32,  "A",     s->tm->i_dq[1],           I_Q,             1.0f, "A",                   \
    "measured q current (rotor frame at the angle in use)")                                               \
  X(i_ds_est,        F32,  "A",     s->tm->law_tm.i_ds,       I_DS,            1.0f, "A",                   \
    "the law's stator-flux-frame current along the flux (flux laws; 0 for FOC)")                          \
  X(i_qs_est,        F32,  "A",     s->tm->law_tm.i_qs,       I_QS,            1.0f, "A",                   \
    "the law's stator-flux-frame torque current (flux laws; 0 for FOC)")                                  \
  X(i_qs_ref,        F32,  "A",     s->tm->law_tm.i_qs_ref,   I_QS_REF,        1.0f, "A",                   \
    "DFVC torque-current reference")                                                                      \
  X(flux_ref,        F32,  "Vs",    s->tm->law_tm.flux_ref,   FLUX_REF,        1.0f, "Vs",                  \
    "DFVC flux reference")                                                                                \
  X(flux_est,        F32,  "Vs",    s->tm->law_tm.flux,       FLUX,            1.0f, "Vs",                  \
    "the law's stator flux amplitude estimate")                                                           \
  X(delta_est,       F32,  "rad",   ctrl_tm_delta(&s->tm->law_tm), DELTA,      1.0f, "rad",                 \
    "the law's load angle estimate")                                                                      \
  X(v_dc_meas,       F32,  "V",     s->tm->v_dc,              V_DC,            1.0f, "V",                   \
    "measured DC-link voltage")                                                                           \
  X(duty_a,          F32,  "1",     s->tm->duty[0],           NONE,            1.0f, "",                    \
    "duty a of the pattern this ISR wrote, as the HAL applies it (board range, rounding)")                \
  X(duty_b,          F32,  "1",     s->tm->duty[1],           NONE,            1.0f, "",                    \
    "duty b, as duty_a")                                                                                  \
  X(duty_c,          F32,  "1",     s->tm->duty[2],           NONE,            1.0f, "",                    \
    "duty c, as duty_a")                                                                                  \
  X(state,           U32,  "",      (double)s->tm->state,     STATE,           1.0f, "",                    \
    "0 idle, 1 offset calibration, 2 run, 3 fault, 4 align (docs/parameters.md)")                         \
  X(faults,          U32,  "bits",  (double)s->tm->faults,    FAULTS,          1.0f, "",                    \
    "latched fault bits (docs/parameters.md, Fault bits)")                                                \
  X(theta_e_est,     F32,  "rad",   s->tm->theta_e,           NONE,            1.0f, "",                    \
    "electrical angle in use at the current sample")                                                      \
  X(lc_cause,        U32,  "bits",  (double)s->tm->lc_cause,  NONE,            1.0f, "",                    \
    "the loss-of-control conditions that tripped: 1 current, 2 load angle, 4 torque, 8 flux, "            \
    "16 observer, 32 run-away (the speed loop's check, docs/faults.md)")                                  \
  X(torque_max,      F32,  "N m",   s->drv->torque_max_avail, NONE,            1.0f, "",                    \
    "torque the law can deliver now (the speed loop's limit)")                                            \
  X(load_torque_est, F32,  "N m",   s->tm->load_est,          LOAD_TORQUE_EST, 1.0f, "N m",                 \
    "the position source's load-torque estimate (Kalman filter sources dfc+kf, ivd+kf, ekf, "             \
    "ivd+kf+rls: x_3 of (4.46); 0 otherwise)")                                                            \
  X(pos_err,         F32,  "rad",   s->tm->pos_health,        POS_ERR,         1.0f, "rad",                 \
    "position source: distance of this period's measurement from its prediction (electrical)")            \
  X(rls_ok,          BOOL, "0/1",   s->tm->rls_ok ? 1.0f : 0.0f, RLS_OK,       1.0f, "",                    \
    "ivd+kf+rls: 1 when the identified a, b have settled (docs/dfc.md, RLS health); 0 before, "           \
    "when they cannot, and for the other sources")                                                        \
  X(pos_emf_res,     F32,  "1",     s->drv->pos_chk.res,       NONE,            1.0f, "",                    \
    "position plausibility (encoder): the voltage-model residual over its tolerance at the last "         \
    "slow-period check (above 1: counted towards the position trip; docs/faults.md)")
/* clang-format on */

#endif
