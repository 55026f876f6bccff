/*
 * can_socketcan.c - SocketCAN raw transport for the SIL (see
 * can_socketcan.h).
 */
#define _DEFAULT_SOURCE
#include "can_socketcan.h"

#include <stdio.h>
#include <string.h>

#if defined(__linux__) && defined(__has_include)
// cppcheck-suppress preprocessorErrorDirective
#if __has_include(<linux/can.h>) && __has_include(<linux/can/raw.h>)
#define FD_HAVE_SOCKETCAN 1
#endif
#endif

#ifdef FD_HAVE_SOCKETCAN
#include <errno.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

int can_socketcan_open(can_socketcan_t *s, const char *ifname, char *err, size_t errlen) {
  memset(s, 0, sizeof *s);
  s->fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s->fd < 0) {
    if (errno == EAFNOSUPPORT || errno == EPROTONOSUPPORT) {
      snprintf(err, errlen,
               "this kernel has no SocketCAN (AF_CAN): use --can socketcand:PORT instead");
    } else {
      snprintf(err, errlen, "SocketCAN socket: %s", strerror(errno));
    }
    return -1;
  }
  struct ifreq ifr;
  memset(&ifr, 0, sizeof ifr);
  size_t len = strlen(ifname);
  if (len >= sizeof ifr.ifr_name) {
    snprintf(err, errlen, "%s: interface name too long", ifname);
    close(s->fd);
    s->fd = -1;
    return -1;
  }
  memcpy(ifr.ifr_name, ifname, len + 1);
  struct sockaddr_can addr;
  memset(&addr, 0, sizeof addr);
  addr.can_family = AF_CAN;
  if (ioctl(s->fd, SIOCGIFINDEX, &ifr) != 0) {
    snprintf(err, errlen,
             "%s: %s (for a virtual bus: ip link add dev %s type vcan && ip link set up %s)",
             ifname, strerror(errno), ifname, ifname);
    close(s->fd);
    s->fd = -1;
    return -1;
  }
  addr.can_ifindex = ifr.ifr_ifindex;
  int fl = fcntl(s->fd, F_GETFL, 0);
  if (bind(s->fd, (struct sockaddr *)&addr, sizeof addr) != 0 || fl < 0 ||
      fcntl(s->fd, F_SETFL, fl | O_NONBLOCK) != 0) {
    snprintf(err, errlen, "%s: %s", ifname, strerror(errno));
    close(s->fd);
    s->fd = -1;
    return -1;
  }
  return 0;
}

void can_socketcan_poll(can_socketcan_t *s, hal_sil_t *hal) {
  if (s->fd < 0) {
    return;
  }
  for (unsigned n = 0; n < HAL_SIL_CAN_QUEUE; ++n) {
    if (hal->can_rx.head - hal->can_rx.tail >= HAL_SIL_CAN_QUEUE) {
      break;
    }
    struct can_frame cf;
    ssize_t r = read(s->fd, &cf, sizeof cf);
    if (r != (ssize_t)sizeof cf) {
      break;
    }
    if ((cf.can_id & (CAN_RTR_FLAG | CAN_ERR_FLAG)) != 0u) {
      continue;
    }
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.extended = (cf.can_id & CAN_EFF_FLAG) != 0u;
    f.id = cf.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    f.dlc = cf.can_dlc > 8u ? 8u : cf.can_dlc;
    memcpy(f.data, cf.data, f.dlc);
    hal_sil_can_push(&hal->can_rx, &f);
    s->rx_frames++;
  }
  hal_can_frame_t f;
  while (hal_sil_can_pop(&hal->can_tx, &f)) {
    struct can_frame cf;
    memset(&cf, 0, sizeof cf);
    cf.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
    cf.can_dlc = f.dlc > 8u ? 8u : f.dlc;
    memcpy(cf.data, f.data, cf.can_dlc);
    if (write(s->fd, &cf, sizeof cf) != (ssize_t)sizeof cf) {
      s->dropped++;
    } else {
      s->tx_frames++;
    }
  }
}

void can_socketcan_close(can_socketcan_t *s) {
  if (s->fd >= 0) {
    close(s->fd);
  }
  s->fd = -1;
}

#else /* no <linux/can.h> */

int can_socketcan_open(can_socketcan_t *s, const char *ifname, char *err, size_t errlen) {
  memset(s, 0, sizeof *s);
  s->fd = -1;
  snprintf(err, errlen,
           "%s: SocketCAN is not available in this build (no <linux/can.h>): use "
           "--can socketcand:PORT",
           ifname);
  return -1;
}

void can_socketcan_poll(can_socketcan_t *s, hal_sil_t *hal) {
  (void)s;
  (void)hal;
}

void can_socketcan_close(can_socketcan_t *s) {
  s->fd = -1;
}

#endif
