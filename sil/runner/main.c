/*
 * main.c - fluxdrive-sil: run one scenario.
 *
 *   fluxdrive-sil SCENARIO.json [--log PATH.npy] [--summary PATH.json]
 *                 [--decimate N] [--bench] [--print-config]
 *
 * --print-config prints the resolved parameters (JSON) and exits.
 * --record-isr PATH.bin records every ISR's inputs and outputs for the PIL
 * replay (sil/runner/isr_record.h, docs/pil.md).
 * Exit codes: 0 ran (faults are results, reported in the summary),
 * 1 I/O error, 2 bad scenario or usage.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "isr_record.h"
#include "log_npy.h"
#include "scenario.h"
#include "sil_run.h"
#include "summary.h"

static int usage(void) {
  fprintf(stderr, "usage: fluxdrive-sil SCENARIO.json [--log PATH.npy] [--summary PATH.json]\n"
                  "                     [--decimate N] [--bench] [--print-config]\n"
                  "                     [--record-isr PATH.bin]\n");
  return 2;
}

int main(int argc, char **argv) {
  const char *scenario = NULL, *log_path = NULL, *summary_path = NULL, *record_path = NULL;
  int decimate = 0, bench = 0, print_config = 0;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--log") == 0 && i + 1 < argc) {
      log_path = argv[++i];
    } else if (strcmp(argv[i], "--summary") == 0 && i + 1 < argc) {
      summary_path = argv[++i];
    } else if (strcmp(argv[i], "--decimate") == 0 && i + 1 < argc) {
      char *end = NULL;
      long v = strtol(argv[++i], &end, 10);
      if (end == NULL || *end != '\0' || v < 1 || v > 1000000) {
        fprintf(stderr, "fluxdrive-sil: --decimate: must be an integer in [1, 1000000]\n");
        return 2;
      }
      decimate = (int)v;
    } else if (strcmp(argv[i], "--record-isr") == 0 && i + 1 < argc) {
      record_path = argv[++i];
    } else if (strcmp(argv[i], "--bench") == 0) {
      bench = 1;
    } else if (strcmp(argv[i], "--print-config") == 0) {
      print_config = 1;
    } else if (argv[i][0] == '-' || scenario != NULL) {
      return usage();
    } else {
      scenario = argv[i];
    }
  }
  if (scenario == NULL) {
    return usage();
  }
  static scenario_t sc;
  char err[512];
  if (scenario_load_file(scenario, &sc, err, sizeof err) != 0) {
    fprintf(stderr, "fluxdrive-sil: %s\n", err);
    return 2;
  }
  if (print_config) {
    char *js = config_json(&sc);
    if (js == NULL) {
      return 1;
    }
    printf("%s\n", js);
    free(js);
    return 0;
  }
  if (decimate > 0) {
    sc.log_decimation = decimate;
  }
  log_npy_t lg;
  int logging = log_path != NULL && !bench;
  if (logging && log_npy_open(&lg, log_path, sc.log_decimation) != 0) {
    fprintf(stderr, "fluxdrive-sil: %s: cannot write the log\n", log_path);
    return 1;
  }
  sil_observer_fn obs = logging ? log_npy_observer : NULL;
  void *obs_user = logging ? &lg : NULL;
  static isr_record_t rec;
  if (record_path != NULL) {
    if (isr_record_open(&rec, record_path) != 0) {
      fprintf(stderr, "fluxdrive-sil: %s: cannot write the ISR record\n", record_path);
      return 1;
    }
    rec.next = obs;
    rec.next_user = obs_user;
    obs = isr_record_observer;
    obs_user = &rec;
  }
  sil_result_t res;
  int r = sil_run(&sc, obs, obs_user, &res, err, sizeof err);
  if (record_path != NULL && isr_record_close(&rec) != 0) {
    fprintf(stderr, "fluxdrive-sil: %s: writing the ISR record failed\n", record_path);
    return 1;
  }
  if (logging && log_npy_close(&lg) != 0) {
    fprintf(stderr, "fluxdrive-sil: %s: writing the log failed\n", log_path);
    return 1;
  }
  if (r != 0) {
    fprintf(stderr, "fluxdrive-sil: %s: %s\n", scenario, err);
    return 2;
  }
  if (bench) {
    printf("steps: %llu\nwall: %.3f s\nreal-time factor: %.1f\n", (unsigned long long)res.steps,
           res.wall_time, res.real_time_factor);
    return 0;
  }
  char *js = summary_json(&sc, &res);
  if (js == NULL) {
    return 1;
  }
  printf("%s\n", js);
  int rc = 0;
  if (summary_path != NULL) {
    FILE *f = fopen(summary_path, "w");
    if (f == NULL || fprintf(f, "%s\n", js) < 0) {
      fprintf(stderr, "fluxdrive-sil: %s: cannot write the summary\n", summary_path);
      rc = 1;
    }
    if (f != NULL) {
      fclose(f);
    }
  }
  free(js);
  return rc;
}
