/*
 * fuzz_scenario.c - libFuzzer harness: the scenario parser
 * (sil/runner/scenario.c, scenario_parse) on arbitrary bytes.
 *
 * Checked (docs/fuzzing.md), __builtin_trap() on a violation:
 *   - scenario_parse returns 0 or -1;
 *   - on -1 the message is NUL-terminated within its buffer, not empty,
 *     valid UTF-8 (RFC 3629) and starts with the origin ("fuzz.json: ");
 *   - on 0 the scenario sets up the plant, the SIL HAL and the drive
 *     (sil_setup: plant_init, drive_init) or fails cleanly with a message,
 *     and then runs one main-loop period (references, ISRs, plant) without
 *     a sanitizer report.
 * Map files named by machine.map resolve as in the runner (the repository's
 * maps); .npz / .csv conversion is pointed at /bin/false (no tool runs).
 */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drive.h"
#include "scenario.h"
#include "sil_run.h"

#define ORIGIN "fuzz.json"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static scenario_t sc;
static sil_ctx_t x;

static void violated(const char *what, const char *msg) {
  fprintf(stderr, "fuzz_scenario: invariant violated: %s\n", what);
  if (msg != NULL) {
    fprintf(stderr, "fuzz_scenario: message: \"%s\"\n", msg);
  }
  __builtin_trap();
}

/* Whether s[0..n) is valid UTF-8 (RFC 3629: no overlong forms, no
 * surrogates, nothing beyond U+10FFFF). */
static bool utf8_valid(const unsigned char *s, size_t n) {
  size_t i = 0;
  while (i < n) {
    const unsigned char b = s[i];
    size_t len;
    unsigned char lo = 0x80u, hi = 0xBFu;
    if (b < 0x80u) {
      len = 1u;
    } else if (b >= 0xC2u && b <= 0xDFu) {
      len = 2u;
    } else if (b >= 0xE0u && b <= 0xEFu) {
      len = 3u;
      lo = b == 0xE0u ? 0xA0u : 0x80u;
      hi = b == 0xEDu ? 0x9Fu : 0xBFu;
    } else if (b >= 0xF0u && b <= 0xF4u) {
      len = 4u;
      lo = b == 0xF0u ? 0x90u : 0x80u;
      hi = b == 0xF4u ? 0x8Fu : 0xBFu;
    } else {
      return false;
    }
    if (i + len > n) {
      return false;
    }
    for (size_t k = 1; k < len; ++k) {
      const unsigned char c = s[i + k];
      if (k == 1u ? (c < lo || c > hi) : (c & 0xC0u) != 0x80u) {
        return false;
      }
    }
    i += len;
  }
  return true;
}

static void check_message(const char *err, size_t cap) {
  const char *nul = memchr(err, '\0', cap);
  if (nul == NULL) {
    violated("error message not NUL-terminated", NULL);
  }
  const size_t n = (size_t)(nul - err);
  if (n == 0u) {
    violated("error message empty", NULL);
  }
  if (!utf8_valid((const unsigned char *)err, n)) {
    violated("error message not valid UTF-8", err);
  }
  if (strncmp(err, ORIGIN ": ", sizeof ORIGIN + 1u) != 0) {
    violated("error message does not start with the origin", err);
  }
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc;
  (void)argv;
  setenv("FLUXDRIVE_PYTHON", "/bin/false", 1); /* no map conversion */
  return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *json = malloc(size + 1u);
  if (json == NULL) {
    return 0;
  }
  memcpy(json, data, size);
  json[size] = '\0';
  char err[512];
  memset(err, 'x', sizeof err); /* no NUL unless the parser writes one */
  const int r = scenario_parse(json, ORIGIN, &sc, err, sizeof err);
  free(json);
  if (r != 0 && r != -1) {
    violated("scenario_parse returned neither 0 nor -1", NULL);
  }
  if (r != 0) {
    check_message(err, sizeof err);
    return 0;
  }
  memset(err, 'x', sizeof err);
  if (sil_setup(&x, &sc, err, sizeof err) != 0) {
    const char *nul = memchr(err, '\0', sizeof err);
    if (nul == NULL || nul == err) {
      violated("set-up error message empty or not NUL-terminated", NULL);
    }
    return 0;
  }
  /* one main-loop period: references, background, slow_div ISRs, plant */
  sil_command_references(&x.drv, &sc, 0.0);
  sil_main_injections(&x, &sc, 0.0);
  drive_background(&x.drv);
  for (uint32_t k = 0; k < sc.drive.slow_div; ++k) {
    const double t = (double)k * sc.plant.ts;
    x.hal.time_us = (uint32_t)(uint64_t)(t * 1e6);
    sil_sample(&x, &sc, t);
    drive_isr(&x.drv);
    sil_advance(&x, &sc, t);
  }
  return 0;
}
