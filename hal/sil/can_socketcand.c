/*
 * can_socketcand.c - socketcand server for the SIL (see can_socketcand.h).
 */
#define _DEFAULT_SOURCE
#include "can_socketcand.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

/* Frames are held back (buffered) this long after the raw-mode "< ok >":
 * python-can reads that reply with one recv() and needs it alone. */
#define RAW_SETTLE_S 0.1

static double wall_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int set_nonblock(int fd) {
  int fl = fcntl(fd, F_GETFL, 0);
  return fl < 0 ? -1 : fcntl(fd, F_SETFL, fl | O_NONBLOCK);
}

int can_socketcand_open(can_socketcand_t *s, uint16_t port, char *err, size_t errlen) {
  memset(s, 0, sizeof *s);
  for (int i = 0; i < CAN_SCD_CLIENTS; ++i) {
    s->cl[i].fd = -1;
  }
  s->listen_fd = socket(AF_INET, SOCK_STREAM, 0);
  if (s->listen_fd < 0) {
    snprintf(err, errlen, "socket: %s", strerror(errno));
    return -1;
  }
  int one = 1;
  setsockopt(s->listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  struct sockaddr_in a;
  memset(&a, 0, sizeof a);
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  if (bind(s->listen_fd, (struct sockaddr *)&a, sizeof a) != 0 || listen(s->listen_fd, 4) != 0 ||
      set_nonblock(s->listen_fd) != 0 ||
      getsockname(s->listen_fd, (struct sockaddr *)&a, &len) != 0) {
    snprintf(err, errlen, "127.0.0.1:%u: %s", (unsigned)port, strerror(errno));
    close(s->listen_fd);
    s->listen_fd = -1;
    return -1;
  }
  s->port = ntohs(a.sin_port);
  can_socketcand_seed(s, 1u);
  return 0;
}

void can_socketcand_seed(can_socketcand_t *s, uint64_t seed) {
  can_link_init(&s->rx, seed);
  can_link_init(&s->tx, seed + 1u);
}

uint16_t can_socketcand_port(const can_socketcand_t *s) {
  return s->port;
}

int can_socketcand_clients(const can_socketcand_t *s) {
  int n = 0;
  for (int i = 0; i < CAN_SCD_CLIENTS; ++i) {
    n += s->cl[i].fd >= 0 && s->cl[i].phase == 2;
  }
  return n;
}

static void drop_client(can_scd_client_t *c) {
  if (c->fd >= 0) {
    close(c->fd);
  }
  c->fd = -1;
  c->phase = 0;
  c->in_len = c->out_len = 0;
}

/* Appends text to the client's output; false (nothing written) when full. */
static int out_put(can_scd_client_t *c, const char *txt, size_t n) {
  if (c->fd < 0 || c->out_len + n > sizeof c->out) {
    return 0;
  }
  memcpy(c->out + c->out_len, txt, n);
  c->out_len += n;
  return 1;
}

static void flush_client(can_scd_client_t *c) {
  if (c->phase == 2 && wall_now() - c->raw_at < RAW_SETTLE_S) {
    return; /* frames wait until the client has read the raw-mode "< ok >" */
  }
  while (c->fd >= 0 && c->out_len > 0) {
    ssize_t w = send(c->fd, c->out, c->out_len, MSG_NOSIGNAL);
    if (w < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        drop_client(c);
      }
      return;
    }
    memmove(c->out, c->out + w, c->out_len - (size_t)w);
    c->out_len -= (size_t)w;
  }
}

static void accept_clients(can_socketcand_t *s) {
  for (;;) {
    int fd = accept(s->listen_fd, NULL, NULL);
    if (fd < 0) {
      return;
    }
    can_scd_client_t *c = NULL;
    for (int i = 0; i < CAN_SCD_CLIENTS && c == NULL; ++i) {
      if (s->cl[i].fd < 0) {
        c = &s->cl[i];
      }
    }
    if (c == NULL || set_nonblock(fd) != 0) {
      close(fd); /* bus full */
      continue;
    }
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    c->fd = fd;
    c->phase = 0;
    c->since = wall_now();
    c->in_len = c->out_len = 0;
    out_put(c, "< hi >", 6);
    flush_client(c);
  }
}

static int hexval(char ch) {
  if (ch >= '0' && ch <= '9') {
    return ch - '0';
  }
  if (ch >= 'a' && ch <= 'f') {
    return ch - 'a' + 10;
  }
  if (ch >= 'A' && ch <= 'F') {
    return ch - 'A' + 10;
  }
  return -1;
}

/* A hex token of 1..maxdig digits; -1 if malformed. */
static long parse_hex(const char *tok, size_t maxdig) {
  size_t n = strlen(tok);
  if (n == 0 || n > maxdig) {
    return -1;
  }
  long v = 0;
  for (size_t i = 0; i < n; ++i) {
    int h = hexval(tok[i]);
    if (h < 0) {
      return -1;
    }
    v = v * 16 + h;
  }
  return v;
}

/* "< send ID LEN B0 .. >" tokens after "send"; 0 on success. */
static int parse_send(char **tok, int ntok, hal_can_frame_t *f) {
  if (ntok < 2) {
    return -1;
  }
  size_t idlen = strlen(tok[0]);
  long id = parse_hex(tok[0], 8);
  long len = parse_hex(tok[1], 1);
  if (id < 0 || len < 0 || len > 8 || ntok != 2 + len) {
    return -1;
  }
  memset(f, 0, sizeof *f);
  f->extended = idlen > 3;
  if ((!f->extended && id > 0x7FF) || id > 0x1FFFFFFF) {
    return -1;
  }
  f->id = (uint32_t)id;
  f->dlc = (uint8_t)len;
  for (long i = 0; i < len; ++i) {
    long b = parse_hex(tok[2 + i], 2);
    if (b < 0) {
      return -1;
    }
    f->data[i] = (uint8_t)b;
  }
  return 0;
}

static void format_frame(const hal_can_frame_t *f, double t, char *buf, size_t n) {
  unsigned long long us = t > 0.0 ? (unsigned long long)(t * 1e6 + 0.5) : 0ull;
  char hex[17];
  size_t dlc = f->dlc > 8u ? 8u : f->dlc;
  // cppcheck-suppress knownConditionTrueFalse ; dlc comes from the frame
  for (size_t i = 0; i < dlc; ++i) {
    snprintf(hex + 2u * i, 3, "%02X", f->data[i]);
  }
  hex[2u * (size_t)dlc] = '\0';
  if (f->extended) {
    snprintf(buf, n, "< frame %08X %llu.%06llu %s >", (unsigned)(f->id & 0x1FFFFFFFu),
             us / 1000000ull, us % 1000000ull, hex);
  } else {
    snprintf(buf, n, "< frame %03X %llu.%06llu %s >", (unsigned)(f->id & 0x7FFu), us / 1000000ull,
             us % 1000000ull, hex);
  }
}

static int queue_room(const hal_sil_can_queue_t *q) {
  return q->head - q->tail < HAL_SIL_CAN_QUEUE;
}

/* The frames the rx link releases by t, into the drive's queue while it has
 * room (the rest wait in the link, then in the sockets). */
static void drain_rx(can_socketcand_t *s, hal_sil_t *hal, double t) {
  hal_can_frame_t f;
  while (queue_room(&hal->can_rx) && can_link_take(&s->rx, t, &f, NULL)) {
    hal_sil_can_push(&hal->can_rx, &f);
  }
}

/* To every raw-mode client but number `except` (-1: none). */
static void broadcast(can_socketcand_t *s, const hal_can_frame_t *f, double t, int except) {
  char line[96];
  format_frame(f, t, line, sizeof line);
  size_t n = strlen(line);
  for (int i = 0; i < CAN_SCD_CLIENTS; ++i) {
    can_scd_client_t *c = &s->cl[i];
    if (i == except || c->fd < 0 || c->phase != 2) {
      continue;
    }
    if (!out_put(c, line, n)) {
      s->dropped++;
    }
  }
}

/* Executes one "< ... >" command (text without the brackets). Returns 0,
 * or 1 when a frame could not be queued (retry later). */
static int do_command(can_socketcand_t *s, can_scd_client_t *c, char *cmd, hal_sil_t *hal,
                      double t) {
  char *tok[16];
  int ntok = 0;
  for (char *p = strtok(cmd, " \t\r\n"); p != NULL && ntok < 16; p = strtok(NULL, " \t\r\n")) {
    tok[ntok++] = p;
  }
  if (ntok == 0) {
    s->bad_commands++;
    return 0;
  }
  if (c->phase == 0 && strcmp(tok[0], "open") == 0 && ntok == 2) {
    c->phase = 1;
    out_put(c, "< ok >", 6);
    flush_client(c);
  } else if (c->phase == 1 && strcmp(tok[0], "rawmode") == 0 && ntok == 1) {
    out_put(c, "< ok >", 6);
    flush_client(c); /* alone: python-can reads it with one recv() */
    c->phase = 2;
    c->raw_at = wall_now();
  } else if (c->phase == 2 && strcmp(tok[0], "send") == 0) {
    hal_can_frame_t f;
    if (parse_send(tok + 1, ntok - 1, &f) != 0) {
      s->bad_commands++;
      return 0;
    }
    drain_rx(s, hal, t);
    if (!queue_room(&hal->can_rx) || !can_link_offer(&s->rx, &f, t)) {
      return 1;
    }
    drain_rx(s, hal, t);
    s->rx_frames++;
    broadcast(s, &f, t, (int)(c - s->cl));
  } else if (strcmp(tok[0], "echo") == 0 && ntok == 1) {
    out_put(c, "< echo >", 8);
  } else {
    s->bad_commands++;
  }
  return 0;
}

/* Parses complete commands from the client's input buffer. */
static void parse_input(can_socketcand_t *s, can_scd_client_t *c, hal_sil_t *hal, double t) {
  size_t pos = 0;
  while (pos < c->in_len && c->fd >= 0) {
    char *start = memchr(c->in + pos, '<', c->in_len - pos);
    if (start == NULL) {
      s->bad_commands += 1;
      pos = c->in_len; /* garbage without a command start */
      break;
    }
    if (start != c->in + pos) {
      s->bad_commands++; /* garbage before '<' */
      pos = (size_t)(start - c->in);
    }
    char *end = memchr(start, '>', c->in_len - pos);
    if (end == NULL) {
      if (c->in_len - pos > CAN_SCD_CMD_MAX) {
        s->bad_commands++; /* too long: skip to the next '<' */
        char *next = memchr(start + 1, '<', c->in_len - pos - 1);
        pos = next != NULL ? (size_t)(next - c->in) : c->in_len;
        continue;
      }
      break; /* incomplete: wait for more */
    }
    size_t n = (size_t)(end - start) - 1;
    if (n > CAN_SCD_CMD_MAX) {
      s->bad_commands++;
      pos = (size_t)(end - c->in) + 1;
      continue;
    }
    char cmd[CAN_SCD_CMD_MAX + 1];
    memcpy(cmd, start + 1, n);
    cmd[n] = '\0';
    if (memchr(cmd, '<', n) != NULL) {
      s->bad_commands++; /* "< .. < .. >": resync on the inner '<' */
      pos = (size_t)((char *)memchr(start + 1, '<', n) - c->in);
      continue;
    }
    if (do_command(s, c, cmd, hal, t) != 0) {
      break; /* HAL queue full: keep this command for the next poll */
    }
    pos = (size_t)(end - c->in) + 1;
  }
  memmove(c->in, c->in + pos, c->in_len - pos);
  c->in_len -= pos;
}

static void read_client(can_socketcand_t *s, can_scd_client_t *c, hal_sil_t *hal, double t) {
  if (c->in_len < sizeof c->in) {
    ssize_t r = recv(c->fd, c->in + c->in_len, sizeof c->in - c->in_len, 0);
    if (r == 0 || (r < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      drop_client(c);
      return;
    }
    if (r > 0) {
      c->in_len += (size_t)r;
    }
  }
  parse_input(s, c, hal, t);
}

void can_socketcand_poll(can_socketcand_t *s, hal_sil_t *hal, double t) {
  if (s->listen_fd < 0) {
    return;
  }
  /* first free the slots of clients that never finished the handshake */
  const double now = wall_now();
  for (int i = 0; i < CAN_SCD_CLIENTS; ++i) {
    if (s->cl[i].fd >= 0 && s->cl[i].phase != 2 && now - s->cl[i].since > CAN_SCD_HANDSHAKE_S) {
      s->handshake_timeouts++;
      drop_client(&s->cl[i]);
    }
  }
  accept_clients(s);
  for (int i = 0; i < CAN_SCD_CLIENTS; ++i) {
    if (s->cl[i].fd >= 0) {
      read_client(s, &s->cl[i], hal, t);
    }
  }
  drain_rx(s, hal, t); /* delayed frames now due */
  hal_can_frame_t f;
  while (can_link_room(&s->tx) && hal_sil_can_pop(&hal->can_tx, &f)) {
    s->tx_frames++;
    (void)can_link_offer(&s->tx, &f, t);
  }
  while (can_link_take(&s->tx, t, &f, NULL)) {
    broadcast(s, &f, t, -1);
  }
  for (int i = 0; i < CAN_SCD_CLIENTS; ++i) {
    flush_client(&s->cl[i]);
  }
}

void can_socketcand_close(can_socketcand_t *s) {
  for (int i = 0; i < CAN_SCD_CLIENTS; ++i) {
    drop_client(&s->cl[i]);
  }
  if (s->listen_fd >= 0) {
    close(s->listen_fd);
  }
  s->listen_fd = -1;
}
