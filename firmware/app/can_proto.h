/*
 * can_proto.h - the CAN protocol of the drive (can/fluxdrive.dbc): commands,
 * parameter get/set with replies, status, telemetry, heartbeat, command
 * timeout. Runs in the slow-loop context, never in the ISR:
 *
 *   can_proto_poll(&p, &drv, hal_time_us());   each slow period, before
 *   drive_slow_loop(&drv);                      the slow loop (commands are
 *                                               staged through drive_cmd_*
 *                                               and take effect there)
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
 * torque in force to zero over ramp_ms; then drive_raise_fault(
 * DRIVE_FAULT_CMD_TIMEOUT) turns the gates off and latches the fault, and
 * the references are zeroed (speed, torque, currents; the previous mode is
 * restored) so that clear_fault + enable restarts from rest. During the
 * ramp, CMD_* frames are answered timed_out and not applied.
 */
#ifndef FLUXDRIVE_CAN_PROTO_H
#define FLUXDRIVE_CAN_PROTO_H

#include <stdbool.h>
#include <stdint.h>

#include "can_codec.h"
#include "drive.h"
#include "hal.h"

#define CAN_PROTO_RX_MAX 16u /* frames read per call */

/* Periodic transmissions (index of can_proto_cfg_t.period_ms). */
typedef enum {
  CAN_PERIOD_STATUS = 0,
  CAN_PERIOD_HEARTBEAT,
  CAN_PERIOD_TM_SPEED,
  CAN_PERIOD_TM_TORQUE,
  CAN_PERIOD_TM_PHASE,
  CAN_PERIOD_TM_DQ,
  CAN_PERIOD_TM_FLUX,
  CAN_PERIOD_COUNT
} can_period_t;

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
  /* last STATUS content sent (a change sends one at once) */
  drive_state_t st_state;
  uint32_t st_faults;
  bool st_ramp;
} can_proto_t;

void can_proto_cfg_default(can_proto_cfg_t *cfg);
/* Returns 0, or -1 when cfg is invalid (node above CAN_NODE_MAX). */
int can_proto_init(can_proto_t *p, const can_proto_cfg_t *cfg);
void can_proto_poll(can_proto_t *p, drive_t *drv, uint32_t now_us);

/* Protocol parameters (ids of the reply_param table from 64): node (read
 * only), timeout, ramp and the periods. Same conventions as drive_params. */
#define CAN_PROTO_PARAM_FIRST 64u
#define CAN_PROTO_PARAM_COUNT (3u + (unsigned)CAN_PERIOD_COUNT)
bool can_proto_param_get(const can_proto_t *p, uint8_t id, float *value);
/* Returns a can_result_t. */
can_result_t can_proto_param_set(can_proto_t *p, uint8_t id, float value);

#endif
