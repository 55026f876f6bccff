/*
 * semihost.c - ARM semihosting calls (see semihost.h).
 */
#include "semihost.h"

#include <string.h>

enum {
  SYS_OPEN = 0x01,
  SYS_CLOSE = 0x02,
  SYS_WRITE0 = 0x04,
  SYS_WRITE = 0x05,
  SYS_READ = 0x06,
  SYS_EXIT_EXTENDED = 0x20,
  ADP_STOPPED_APPLICATION_EXIT = 0x20026,
  OPEN_MODE_RB = 1,
  OPEN_MODE_WB = 5
};

static uint32_t sh_call(uint32_t op, const void *arg) {
  register uint32_t r0 __asm__("r0") = op;
  register const void *r1 __asm__("r1") = arg;
  __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

int32_t sh_open(const char *path, const char *mode) {
  const uint32_t m = (mode[0] == 'w') ? OPEN_MODE_WB : OPEN_MODE_RB;
  const uint32_t args[3] = {(uint32_t)(uintptr_t)path, m, (uint32_t)strlen(path)};
  return (int32_t)sh_call(SYS_OPEN, args);
}

int sh_read(int32_t fd, void *buf, size_t n) {
  const uint32_t args[3] = {(uint32_t)fd, (uint32_t)(uintptr_t)buf, (uint32_t)n};
  return sh_call(SYS_READ, args) == 0u ? 0 : -1; /* returns the bytes not read */
}

int sh_write(int32_t fd, const void *buf, size_t n) {
  const uint32_t args[3] = {(uint32_t)fd, (uint32_t)(uintptr_t)buf, (uint32_t)n};
  return sh_call(SYS_WRITE, args) == 0u ? 0 : -1; /* returns the bytes not written */
}

void sh_close(int32_t fd) {
  const uint32_t args[1] = {(uint32_t)fd};
  (void)sh_call(SYS_CLOSE, args);
}

void sh_puts(const char *s) {
  (void)sh_call(SYS_WRITE0, s);
}

void sh_exit(uint32_t code) {
  const uint32_t args[2] = {ADP_STOPPED_APPLICATION_EXIT, code};
  for (;;) {
    (void)sh_call(SYS_EXIT_EXTENDED, args);
  }
}
