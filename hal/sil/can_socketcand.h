/*
 * can_socketcand.h - a minimal socketcand server (the ASCII protocol of
 * linux-can/socketcand that python-can's `socketcand` interface speaks) on
 * 127.0.0.1:PORT, bridging TCP clients to the SIL HAL's CAN queues.
 *
 *   server: < hi >            client: < open BUS >     server: < ok >
 *   client: < rawmode >       server: < ok >
 *   then    server: < frame ID SECS.USECS HEXDATA >    (ID: 3 hex digits
 *           client: < send ID LEN B0 B1 ... >           standard, 8 extended)
 *
 * Any bus name is accepted. Up to CAN_SCD_CLIENTS clients share the bus: a
 * frame sent by one goes to the drive and to the others, like on a wire.
 * Frame timestamps are the simulated time. Sockets are non-blocking and
 * polled by the runner once per slow period; buffers are bounded:
 *  - receive: a command is pushed to the HAL RX queue only when it has
 *    room, otherwise it waits in the socket (TCP flow control, nothing is
 *    lost); malformed commands and garbage are skipped and counted;
 *  - transmit: per client a bounded buffer; a client that does not read
 *    loses frames (counted), the others do not.
 * Between the clients and the drive each direction passes a can_link_t
 * (can_link.h): injected frame loss and delay (scenario inject.can,
 * docs/scenarios.md), none by default. The clients see each other's frames
 * as sent; the link is the drive's side of the bus.
 */
#ifndef FLUXDRIVE_CAN_SOCKETCAND_H
#define FLUXDRIVE_CAN_SOCKETCAND_H

#include <stddef.h>
#include <stdint.h>

#include "can_link.h"
#include "hal_sil.h"

#define CAN_SCD_CLIENTS 4
/* A client that has not reached raw mode this long after its connection
 * (wall time) is dropped: half-open or idle connections cannot hold the
 * slots (a client's handshake takes milliseconds). */
#define CAN_SCD_HANDSHAKE_S 2.0
#define CAN_SCD_IN          4096
#define CAN_SCD_OUT         65536
#define CAN_SCD_CMD_MAX     128 /* longest command accepted [chars] */

typedef struct {
  int fd;        /* -1: free slot */
  int phase;     /* 0 greeted, 1 bus open, 2 raw mode */
  double raw_at; /* wall time raw mode was acknowledged */
  double since;  /* wall time of the connection */
  size_t in_len, out_len;
  char in[CAN_SCD_IN];
  char out[CAN_SCD_OUT];
} can_scd_client_t;

typedef struct {
  int listen_fd;
  uint16_t port;
  uint32_t rx_frames;          /* frames from clients pushed to the drive */
  uint32_t tx_frames;          /* frames from the drive */
  uint32_t bad_commands;       /* malformed or unknown commands, garbage */
  uint32_t dropped;            /* frames lost on a full client buffer */
  uint32_t handshake_timeouts; /* clients dropped before raw mode (CAN_SCD_HANDSHAKE_S) */
  can_scd_client_t cl[CAN_SCD_CLIENTS];
  can_link_t rx; /* clients -> drive: injected loss and delay */
  can_link_t tx; /* drive -> clients */
} can_socketcand_t;

/* Listens on 127.0.0.1:port (0 = any free port). 0 or -1 with err. */
int can_socketcand_open(can_socketcand_t *s, uint16_t port, char *err, size_t errlen);
uint16_t can_socketcand_port(const can_socketcand_t *s);
/* Seeds the two links' loss generators (rx: seed, tx: seed + 1); their
 * faults are s->rx.fault, s->tx.fault (none after open). */
void can_socketcand_seed(can_socketcand_t *s, uint64_t seed);
/* Clients in raw mode (exchanging frames). */
int can_socketcand_clients(const can_socketcand_t *s);
/* Accepts, reads client commands into hal->can_rx, sends hal->can_tx to
 * the clients stamped with t [s]. Never blocks. */
void can_socketcand_poll(can_socketcand_t *s, hal_sil_t *hal, double t);
void can_socketcand_close(can_socketcand_t *s);

#endif
