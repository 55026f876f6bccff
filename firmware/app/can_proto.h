/*
 * can_proto.h - the CAN protocol of the drive (can/fluxdrive.dbc): commands,
 * parameter get/set with replies, status, telemetry, heartbeat, command
 * timeout. Runs in the main loop, never in the ISR:
 *
 *   can_proto_poll(&p, &drv, hal_time_us());   each slow period; commands
 *   drive_background(&drv);                     are posted (drive_cmd_*) and
 *                                               taken by the next ISR
 *
 * CMD_STATE: enable 0/1, mode and law by number; CAN_KEEP (255) in any of
 * them leaves that setting as it is. An unknown value is out_of_range; a
 * law the machine cannot run (or current mode with a law that has none) is
 * unavailable, and nothing of the frame changes.
 *
 * Receive: at most CAN_PROTO_RX_MAX frames per call (a flood cannot take
 * the slow context's time, and never the ISR's). Frames of other nodes,
 * unknown identifiers and extended identifiers are ignored. Every CMD_* and
 * PARAM_REQ frame for this node gets one REPLY: ok, or the error
 * (bad_dlc, out_of_range naming the signal, ...); on error the reference in
 * force stays. HOST_HB gets none. A reply that finds the TX queue full is
 * kept and retried first at the next call, and no more frames are read
 * until it is out (replies are never lost; telemetry may be).
 *
 * Command timeout: while the drive is enabled (offset calibration or run),
 * if no well-formed frame for this node (command, parameter request or
 * host heartbeat, valid or rejected) arrives for timeout_ms, the drive is
 * put in torque mode and its torque reference ramped linearly from the
 * torque in force to zero over ramp_ms; then drive_request_fault(
 * DRIVE_FAULT_CMD_TIMEOUT) turns the gates off and latches the fault, and
 * the references are zeroed (speed, torque, currents; the previous mode is
 * restored) so that clear_fault + enable restarts from rest. During the
 * ramp, CMD_* frames are answered timed_out and not applied. An
 * identification (CMD_PROC: enabled without an enable) has no torque to
 * ramp: its timeout latches the fault at once (gates off, state fault).
 *
 * CMD_PROC: runs an identification procedure alone (drive_cmd_identify),
 * 255 stops it; TM_PROC: the procedure telemetry (proc.h), one of its
 * PROC_RESULTS results per frame, the index cycling.
 */
#ifndef FLUXDRIVE_CAN_PROTO_H
#define FLUXDRIVE_CAN_PROTO_H

#include <stdbool.h>
#include <stdint.h>

#include "can_codec.h"
#include "drive.h"
#include "hal.h"

#define CAN_PROTO_RX_MAX 16u /* frames read per call */

/* Periodic transmissions: X(ENUM, name, default period [ms]); the index of
 * can_proto_cfg_t.period_ms and, from CAN_PROTO_PARAM_FIRST + 3, the
 * parameter "can_<name>_ms". Append only. */
#define CAN_PERIOD_LIST(X)                                                                         \
  X(STATUS, status, 100)                                                                           \
  X(HEARTBEAT, heartbeat, 500)                                                                     \
  X(TM_SPEED, tm_speed, 10)                                                                        \
  X(TM_TORQUE, tm_torque, 10)                                                                      \
  X(TM_PHASE, tm_phase, 10)                                                                        \
  X(TM_DQ, tm_dq, 10)                                                                              \
  X(TM_FLUX, tm_flux, 10)                                                                          \
  X(TM_CPU, tm_cpu, 100)                                                                           \
  X(TM_POSITION, tm_position, 10)                                                                  \
  X(TM_PROC, tm_proc, 10)

#define CAN_PERIOD_ENUM(E, n, ms) CAN_PERIOD_##E,
typedef enum { CAN_PERIOD_LIST(CAN_PERIOD_ENUM) CAN_PERIOD_COUNT } can_period_t;
#undef CAN_PERIOD_ENUM

typedef struct {
  uint8_t node;                         /* 0..CAN_NODE_MAX */
  uint16_t timeout_ms;                  /* command timeout while enabled, 0 = off */
  uint16_t ramp_ms;                     /* torque ramp to zero on timeout */
  uint16_t period_ms[CAN_PERIOD_COUNT]; /* 0 = not sent */
} can_proto_cfg_t;

typedef struct {
  uint32_t rx_frames;  /* read from the HAL */
  uint32_t rx_ignored; /* unknown identifier / other node / extended */
  uint32_t rx_ok;      /* applied (replied ok) */
  uint32_t rx_errors;  /* rejected (replied with an error) */
  uint32_t tx_dropped; /* periodic frames the TX queue refused */
  uint32_t timeouts;   /* command timeouts */
} can_proto_stats_t;

typedef struct {
  can_proto_cfg_t cfg;
  can_proto_stats_t stats;
  bool started;        /* first poll done */
  uint32_t last_rx_us; /* last well-formed frame for this node */
  uint32_t last_tx_us[CAN_PERIOD_COUNT];
  bool ramp; /* command-timeout ramp running */
  uint32_t ramp_t0_us;
  float ramp_torque0;
  drive_mode_t ramp_mode; /* mode to restore after the timeout */
  bool pending;           /* a reply waits for room in the TX queue */
  hal_can_frame_t pending_frame;
  uint8_t hb_count;
  uint8_t proc_index; /* TM_PROC: the result the next frame carries (0..PROC_RESULTS - 1) */
  /* last STATUS content sent (a change sends one at once) */
  drive_state_t st_state;
  uint32_t st_faults;
  bool st_ramp;
} can_proto_t;

void can_proto_cfg_default(can_proto_cfg_t *cfg);
/* Returns 0, or -1 when cfg is invalid (node above CAN_NODE_MAX). */
int can_proto_init(can_proto_t *p, const can_proto_cfg_t *cfg);
void can_proto_poll(can_proto_t *p, drive_t *drv, uint32_t now_us);

/* Protocol parameters (ids of the reply_param table 64..95): node (read
 * only), timeout, ramp and the periods. Same conventions as drive_params. */
#define CAN_PROTO_PARAM_FIRST 64u
#define CAN_PROTO_PARAM_COUNT (3u + (unsigned)CAN_PERIOD_COUNT)
/* The protocol's ids end here; the drive's go on from it (drive_param_table.h) */
#define CAN_PROTO_PARAM_LAST 96u
_Static_assert(CAN_PROTO_PARAM_FIRST + CAN_PROTO_PARAM_COUNT <= CAN_PROTO_PARAM_LAST,
               "CAN protocol parameters overflow their id range");
/* Name of protocol parameter id ("can_node", "can_status_ms", ...), NULL
 * when there is none. */
const char *can_proto_param_name(uint8_t id);
bool can_proto_param_get(const can_proto_t *p, uint8_t id, float *value);
/* Returns a can_result_t. */
can_result_t can_proto_param_set(can_proto_t *p, uint8_t id, float value);

#endif
