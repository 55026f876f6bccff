/*
 * can_socketcan.h - the SIL HAL's CAN queues on a Linux SocketCAN raw
 * socket (a real adapter such as can0, or a virtual vcan0). Built where
 * <linux/can.h> exists; opening fails with a message where the kernel has
 * no AF_CAN (then use the socketcand transport, can_socketcand.h).
 * Non-blocking, polled once per slow period: at most one HAL queue of
 * frames is read per poll (frames wait in the socket while the queue is
 * full); a frame the socket refuses is dropped and counted.
 */
#ifndef FLUXDRIVE_CAN_SOCKETCAN_H
#define FLUXDRIVE_CAN_SOCKETCAN_H

#include <stddef.h>
#include <stdint.h>

#include "hal_sil.h"

typedef struct {
  int fd;
  uint32_t rx_frames, tx_frames, dropped;
} can_socketcan_t;

/* 0, or -1 with a message in err. */
int can_socketcan_open(can_socketcan_t *s, const char *ifname, char *err, size_t errlen);
void can_socketcan_poll(can_socketcan_t *s, hal_sil_t *hal);
void can_socketcan_close(can_socketcan_t *s);

#endif
