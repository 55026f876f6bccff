/*
 * sil_signal_table.h - the SIL's own log columns: the plant's true state
 * and what the SIL HAL did, one row each (signal_row.h; getters on
 * sil_step_t). With the drive's table (firmware/app/drive_signal_table.h)
 * and the laws' and position sources' signals they make the log's columns
 * (log_columns.c) and docs/log-format.md (`fluxdrive signals --write`).
 *
 * Columns: X(name, type, unit, source, value, doc); value an expression on
 * st (const sil_step_t *) and p (its plant_state_t).
 */
#ifndef FD_SIL_SIGNAL_TABLE_H
#define FD_SIL_SIGNAL_TABLE_H

/* clang-format off */
#define SIL_SIGNAL_TABLE(X)                                                                                \
  X(t,           F32, "s",     "", st->t,                                                                 \
    "time of the sampling instant")                                                                       \
  X(speed,       F32, "rad/s", "plant", p->omega_m,                                                       \
    "true mechanical speed")                                                                              \
  X(torque,      F32, "N m",   "plant", p->torque,                                                        \
    "true electromagnetic torque")                                                                        \
  X(load_torque, F32, "N m",   "plant", p->load_torque,                                                   \
    "load torque in force")                                                                               \
  X(i_a,         F32, "A",     "plant", p->i_abc[0],                                                      \
    "true phase current a")                                                                               \
  X(i_b,         F32, "A",     "plant", p->i_abc[1],                                                      \
    "true phase current b")                                                                               \
  X(i_c,         F32, "A",     "plant", p->i_abc[2],                                                      \
    "true phase current c")                                                                               \
  X(i_d,         F32, "A",     "plant", p->i_dq[0],                                                       \
    "true rotor-frame d current")                                                                         \
  X(i_q,         F32, "A",     "plant", p->i_dq[1],                                                       \
    "true rotor-frame q current")                                                                         \
  X(i_ds,        F32, "A",     "plant", sil_sig_i_fs(p, 0),                                               \
    "true stator-flux-frame current along the flux (Rubino 2020, the (ds, qs) frame)")                   \
  X(i_qs,        F32, "A",     "plant", sil_sig_i_fs(p, 1),                                               \
    "true stator-flux-frame current in quadrature to the flux")                                           \
  X(flux,        F32, "Vs",    "plant", hypot(p->lambda_dq[0], p->lambda_dq[1]),                          \
    "true stator flux amplitude")                                                                         \
  X(delta,       F32, "rad",   "plant", atan2(p->lambda_dq[1], p->lambda_dq[0]),                          \
    "true load angle")                                                                                    \
  X(v_dc,        F32, "V",     "plant", p->v_dc,                                                          \
    "DC-link voltage")                                                                                    \
  X(gates,       U32, "0/1/2", "HAL", st->gates_on ? 1.0 : (st->asc ? 2.0 : 0.0),                          \
    "over [t_k, t_{k+1}): 0 all off, 1 modulating, 2 active short circuit (all low sides on: "           \
    "docs/faults.md, safe state)")                                                                        \
  X(theta_e,     F32, "rad",   "plant", p->theta_e,                                                       \
    "true electrical angle")                                                                              \
  X(theta_e_enc, F32, "rad",   "HAL", st->scenario->plant.machine.pole_pairs * (double)st->adc->enc_angle, \
    "the encoder's reading in electrical radians (pole pairs x mechanical angle; kept for comparison "    \
    "whatever the position source)")                                                                      \
  X(torque_avg,  F32, "N m",   "plant", p->torque_avg,                                                    \
    "the true torque averaged over the period that ends at t (the valley values are instants: with "     \
    "moved pulses, the DFC window, they differ from the averages by the asymmetry of the ripple)")       \
  X(i_d_avg,     F32, "A",     "plant", p->i_dq_avg[0],                                                   \
    "the true d current averaged over the period that ends at t")                                         \
  X(i_q_avg,     F32, "A",     "plant", p->i_dq_avg[1],                                                   \
    "the true q current averaged over the period that ends at t")
/* clang-format on */

#endif
