/*
 * semihost.h - ARM semihosting (BKPT 0xAB on M-profile) as QEMU implements
 * it with -semihosting-config enable=on,target=native: host files and the
 * exit status.
 */
#ifndef FD_PIL_SEMIHOST_H
#define FD_PIL_SEMIHOST_H

#include <stddef.h>
#include <stdint.h>

/* Opens a host file (path relative to QEMU's working directory); mode is
 * "rb" or "wb". Returns the handle or -1. */
int32_t sh_open(const char *path, const char *mode);
/* Reads/writes exactly n bytes; returns 0, or -1 on a short transfer. */
int sh_read(int32_t fd, void *buf, size_t n);
int sh_write(int32_t fd, const void *buf, size_t n);
void sh_close(int32_t fd);
/* Writes a NUL-terminated string to QEMU's stderr/console. */
void sh_puts(const char *s);
/* Ends the emulation; QEMU exits with `code`. */
__attribute__((noreturn)) void sh_exit(uint32_t code);

#endif
