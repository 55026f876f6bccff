/*
 * can_codec.h - the CAN messages of firmware/app/can/fluxdrive.dbc (the
 * source of truth) as tables, and a pack/unpack over them.
 *
 * Hand-written: tests/can/ proves the tables agree with the DBC (every
 * message and signal: identifiers, lengths, bit layout, scale, offset,
 * ranges and value tables) and round-trips frames through this codec and
 * cantools both ways. On the bus, identifier = base (DBC) + node (0..15).
 * All signals are little-endian (Intel), at most 32 bits.
 */
#ifndef FLUXDRIVE_CAN_CODEC_H
#define FLUXDRIVE_CAN_CODEC_H

#include <stdbool.h>
#include <stdint.h>

#define CAN_NODE_MAX 15u

/* Messages, in DBC order. */
typedef enum {
  CAN_MSG_CMD_STATE = 0,
  CAN_MSG_CMD_TORQUE,
  CAN_MSG_CMD_SPEED,
  CAN_MSG_CMD_CURRENT,
  CAN_MSG_CMD_FLUX,
  CAN_MSG_PARAM_REQ,
  CAN_MSG_HOST_HB,
  CAN_MSG_CMD_PROC,
  CAN_MSG_REPLY,
  CAN_MSG_STATUS,
  CAN_MSG_TM_SPEED,
  CAN_MSG_TM_TORQUE,
  CAN_MSG_TM_PHASE,
  CAN_MSG_TM_DQ,
  CAN_MSG_TM_FLUX,
  CAN_MSG_TM_CPU,
  CAN_MSG_TM_POSITION,
  CAN_MSG_TM_PROC,
  CAN_MSG_HEARTBEAT,
  CAN_MSG_COUNT
} can_msg_t;

/* Signals, in DBC order (message by message). REPLY.reply_signal carries
 * the index + 1 of the signal an error concerns (0 = none). */
typedef enum {
  CAN_SIG_ENABLE = 0,
  CAN_SIG_CLEAR_FAULT,
  CAN_SIG_MODE,
  CAN_SIG_LAW,
  CAN_SIG_CMD_TORQUE,
  CAN_SIG_CMD_SPEED_RPM,
  CAN_SIG_CMD_ID,
  CAN_SIG_CMD_IQ,
  CAN_SIG_CMD_FLUX,
  CAN_SIG_PARAM_OP,
  CAN_SIG_PARAM_ID,
  CAN_SIG_PARAM_VALUE,
  CAN_SIG_HOST_HB_COUNT,
  CAN_SIG_CMD_PROC,
  CAN_SIG_REPLY_REQ,
  CAN_SIG_REPLY_RESULT,
  CAN_SIG_REPLY_SIGNAL,
  CAN_SIG_REPLY_PARAM,
  CAN_SIG_REPLY_VALUE,
  CAN_SIG_STATE,
  CAN_SIG_CTRL_MODE,
  CAN_SIG_CTRL_LAW,
  CAN_SIG_FAULTS,
  CAN_SIG_V_DC,
  CAN_SIG_TIMEOUT_RAMP,
  CAN_SIG_CMD_ENABLED,
  CAN_SIG_ERR_COUNT,
  CAN_SIG_SPEED_RPM,
  CAN_SIG_SPEED_REF_RPM,
  CAN_SIG_TORQUE_EST,
  CAN_SIG_TORQUE_REF,
  CAN_SIG_I_A,
  CAN_SIG_I_B,
  CAN_SIG_I_C,
  CAN_SIG_I_D,
  CAN_SIG_I_Q,
  CAN_SIG_I_DS,
  CAN_SIG_I_QS,
  CAN_SIG_FLUX,
  CAN_SIG_FLUX_REF,
  CAN_SIG_DELTA,
  CAN_SIG_I_QS_REF,
  CAN_SIG_ISR_CYCLES_MEAN,
  CAN_SIG_ISR_CYCLES_MAX,
  CAN_SIG_ISR_LOAD,
  CAN_SIG_ISR_OVERRUNS,
  CAN_SIG_LOAD_TORQUE_EST,
  CAN_SIG_POS_ERR,
  CAN_SIG_RLS_OK,
  CAN_SIG_PROC_ID,
  CAN_SIG_PROC_STATUS,
  CAN_SIG_PROC_PHASE,
  CAN_SIG_PROC_INDEX,
  CAN_SIG_PROC_RESULT,
  CAN_SIG_HB_COUNT,
  CAN_SIG_HB_STATE,
  CAN_SIG_COUNT
} can_sig_t;

/* REPLY.reply_result (DBC value table). */
typedef enum {
  CAN_RESULT_OK = 0,
  CAN_RESULT_OUT_OF_RANGE = 1,
  CAN_RESULT_BAD_DLC = 2,
  CAN_RESULT_UNKNOWN_PARAM = 3,
  CAN_RESULT_READ_ONLY = 4,
  CAN_RESULT_NOT_WHILE_RUNNING = 5,
  CAN_RESULT_INCONSISTENT = 6,
  CAN_RESULT_TIMED_OUT = 7,
  CAN_RESULT_UNAVAILABLE = 8 /* law not available on this machine, or mode not on this law */
} can_result_t;
#define CAN_RESULT_COUNT 9u
/* CMD_STATE.enable / mode / law: this value leaves the setting as it is
 * (outside every range of laws and modes). */
#define CAN_KEEP 255u
/* CMD_PROC.cmd_proc: stop the identification running; TM_PROC.proc_id: no
 * procedure since start-up (the procedures are proc.h's ids below it). */
#define CAN_PROC_NONE 255u

typedef struct {
  const char *name;
  uint8_t start;  /* bit, little-endian numbering */
  uint8_t length; /* bits, 1..32 */
  bool is_signed;
  bool is_float; /* IEEE 754 single (length 32) */
  float scale, offset;
  float min, max;           /* physical range (DBC [min|max]) */
  int64_t raw_min, raw_max; /* the same range in raw units (integer signals) */
} can_sig_desc_t;

typedef struct {
  const char *name;
  uint16_t base_id; /* identifier for node 0 */
  uint8_t dlc;
  bool to_drive;     /* sent by the host */
  can_sig_t first;   /* first signal */
  uint8_t n_signals; /* signals first .. first + n - 1 */
} can_msg_desc_t;

const can_msg_desc_t *can_codec_msg(can_msg_t m);
const can_sig_desc_t *can_codec_sig(can_sig_t s);
/* Name of REPLY.reply_result value r ("?" if none). */
const char *can_codec_result_name(unsigned r);

/* Identifier of message m for node. */
uint32_t can_codec_id(can_msg_t m, uint8_t node);
/* The message an identifier carries for node; CAN_MSG_COUNT when none
 * (extended identifiers, other nodes, unknown bases). */
can_msg_t can_codec_lookup(uint32_t id, bool extended, uint8_t node);

/* Raw bits of a signal (zero-extended) and back (masked). */
uint32_t can_codec_get_raw(can_sig_t s, const uint8_t data[8]);
void can_codec_set_raw(can_sig_t s, uint8_t data[8], uint32_t raw);

/* Physical value: raw (sign-extended) * scale + offset, or the float. */
float can_codec_get(can_sig_t s, const uint8_t data[8]);
/* Encodes a physical value, rounded to the nearest step and saturated to
 * what the field can hold (NaN encodes 0). */
void can_codec_set(can_sig_t s, uint8_t data[8], float v);
/* The signal in data is inside its DBC range (exact, on the raw value);
 * for float signals: finite. */
bool can_codec_in_range(can_sig_t s, const uint8_t data[8]);

#endif
