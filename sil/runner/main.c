/*
 * main.c - fluxdrive-sil: run one scenario.
 *
 *   fluxdrive-sil SCENARIO.json [--log PATH.npy] [--summary PATH.json]
 *                 [--decimate N] [--bench] [--print-config]
 *
 * --print-config prints the resolved parameters (JSON) and exits.
 * --print-params prints the parameter table and the drive's named values
 * (JSON; no scenario needed) and exits; --print-signals the signal tables
 * (the log's columns, the CAN signals and PIL fields they fill: JSON, no
 * scenario needed, signals_json.h).
 * --preempt PERIODS [--seed N] [--max-gap-us U] runs PERIODS ISRs of the
 * scenario's plant and drive with the ISR preempting the main loop at
 * random points (sil/runner/sil_preempt.h; at most 600 s of wall time) and
 * prints the result (JSON); exit code 3 when an invariant was violated.
 * --record-isr PATH.bin records every ISR's inputs and outputs for the PIL
 * replay (sil/runner/isr_record.h, docs/pil.md).
 * --can socketcand:PORT | socketcan:IFACE [--node N] [--can-timeout MS]:
 * the drive is commanded over CAN (docs/can.md) and the scenario's
 * references are not applied. socketcand listens on 127.0.0.1:PORT (0: a
 * free port, printed on stderr); the simulation starts when the first
 * client is in raw mode. --realtime paces the simulation to the wall clock
 * (interactive use, the CAN tests); without it the simulation runs as fast
 * as it can and all CAN times (timestamps, timeout) are simulated time.
 * SIGINT/SIGTERM end the run early (the summary is still printed).
 * Exit codes: 0 ran (faults are results, reported in the summary),
 * 1 I/O error, 2 bad scenario or usage.
 */
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_proto.h"
#include "can_socketcan.h"
#include "can_socketcand.h"
#include "isr_record.h"
#include "log_npy.h"
#include "scenario.h"
#include "sil_preempt.h"
#include "signals_json.h"
#include "sil_run.h"
#include "summary.h"

static int usage(void) {
  fprintf(stderr,
          "usage: fluxdrive-sil SCENARIO.json [--log PATH.npy] [--summary PATH.json]\n"
          "                     [--decimate N] [--bench] [--print-config] [--print-params]\n"
          "                     [--print-signals]\n"
          "                     [--record-isr PATH.bin] [--realtime]\n"
          "                     [--preempt PERIODS [--seed N] [--max-gap-us U]]\n"
          "                     [--can socketcand:PORT | --can socketcan:IFACE]\n"
          "                     [--node N] [--can-timeout MS]\n");
  return 2;
}

static volatile int stop_flag;

static void on_signal(int sig) {
  (void)sig;
  stop_flag = 1;
}

/* The transports behind sil_opts_t's callbacks. */
static can_socketcand_t scd;
static can_socketcan_t sck;

/* user: the scenario, for its CAN link faults (inject.can) */
static void io_socketcand(void *user, hal_sil_t *hal, double t) {
  const sil_can_faults_t *cf = &((const scenario_t *)user)->can_faults;
  if (cf->on) {
    sil_can_dir_at(&cf->rx, t, &scd.rx.fault);
    sil_can_dir_at(&cf->tx, t, &scd.tx.fault);
  }
  can_socketcand_poll(&scd, hal, t);
}

static bool ready_socketcand(void *user) {
  (void)user;
  return can_socketcand_clients(&scd) > 0;
}

static void io_socketcan(void *user, hal_sil_t *hal, double t) {
  (void)user;
  (void)t;
  can_socketcan_poll(&sck, hal);
}

static int parse_long(const char *opt, const char *s, long lo, long hi, long *out) {
  char *end = NULL;
  long v = strtol(s, &end, 10);
  if (end == s || *end != '\0' || v < lo || v > hi) {
    fprintf(stderr, "fluxdrive-sil: %s: must be an integer in [%ld, %ld]\n", opt, lo, hi);
    return -1;
  }
  *out = v;
  return 0;
}

int main(int argc, char **argv) {
  const char *scenario = NULL, *log_path = NULL, *summary_path = NULL, *record_path = NULL;
  int decimate = 0, bench = 0, print_config = 0, print_params = 0, print_signals = 0, realtime = 0;
  const char *can = NULL;
  long preempt_n = 0;
  double max_gap_us = 20.0;
  long seed = 1;
  long node = -1, can_timeout = -1;
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
    } else if (strcmp(argv[i], "--realtime") == 0) {
      realtime = 1;
    } else if (strcmp(argv[i], "--can") == 0 && i + 1 < argc) {
      can = argv[++i];
    } else if (strcmp(argv[i], "--node") == 0 && i + 1 < argc) {
      if (parse_long("--node", argv[++i], 0, CAN_NODE_MAX, &node) != 0) {
        return 2;
      }
    } else if (strcmp(argv[i], "--can-timeout") == 0 && i + 1 < argc) {
      if (parse_long("--can-timeout", argv[++i], 0, 60000, &can_timeout) != 0) {
        return 2;
      }
    } else if (strcmp(argv[i], "--print-config") == 0) {
      print_config = 1;
    } else if (strcmp(argv[i], "--print-params") == 0) {
      print_params = 1;
    } else if (strcmp(argv[i], "--print-signals") == 0) {
      print_signals = 1;
    } else if (strcmp(argv[i], "--preempt") == 0 && i + 1 < argc) {
      if (parse_long("--preempt", argv[++i], 1, 100000000, &preempt_n) != 0) {
        return 2;
      }
    } else if (strcmp(argv[i], "--seed") == 0 && i + 1 < argc) {
      if (parse_long("--seed", argv[++i], 0, 0x7fffffff, &seed) != 0) {
        return 2;
      }
    } else if (strcmp(argv[i], "--max-gap-us") == 0 && i + 1 < argc) {
      long g;
      if (parse_long("--max-gap-us", argv[++i], 1, 100000, &g) != 0) {
        return 2;
      }
      max_gap_us = (double)g;
    } else if (argv[i][0] == '-' || scenario != NULL) {
      return usage();
    } else {
      scenario = argv[i];
    }
  }
  if (print_params || print_signals) {
    char *js = print_params ? params_json() : signals_json();
    if (js == NULL) {
      return 1;
    }
    printf("%s\n", js);
    free(js);
    return 0;
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
  if (preempt_n > 0) {
    const sil_preempt_opts_t po = {(uint64_t)preempt_n, 600.0, (uint32_t)seed, max_gap_us};
    static sil_preempt_result_t pr;
    if (sil_preempt_run(&sc, &po, &pr, err, sizeof err) != 0) {
      fprintf(stderr, "fluxdrive-sil: %s\n", err);
      return 2;
    }
    char *js = preempt_json(&pr);
    if (js == NULL) {
      return 1;
    }
    printf("%s\n", js);
    free(js);
    return pr.violations != 0u || pr.tm_torn != 0u ? 3 : 0;
  }
  if (decimate > 0) {
    sc.log_decimation = decimate;
  }
  sil_opts_t opts = {0};
  can_proto_cfg_t pcfg;
  can_proto_cfg_default(&pcfg);
  if (node >= 0) {
    pcfg.node = (uint8_t)node;
  }
  if (can_timeout >= 0) {
    pcfg.timeout_ms = (uint16_t)can_timeout;
  }
  opts.realtime = realtime != 0;
  opts.stop = &stop_flag;
  if (can != NULL) {
    opts.can = &pcfg;
    if (strncmp(can, "socketcand:", 11) == 0) {
      long port;
      if (parse_long("--can socketcand:PORT", can + 11, 0, 65535, &port) != 0) {
        return 2;
      }
      if (can_socketcand_open(&scd, (uint16_t)port, err, sizeof err) != 0) {
        fprintf(stderr, "fluxdrive-sil: --can %s: %s\n", can, err);
        return 2;
      }
      fprintf(stderr, "fluxdrive-sil: socketcand on 127.0.0.1:%u, node %u: waiting for a client\n",
              (unsigned)can_socketcand_port(&scd), (unsigned)pcfg.node);
      fflush(stderr);
      can_socketcand_seed(&scd, sc.can_faults.seed);
      opts.can_io = io_socketcand;
      opts.can_ready = ready_socketcand;
      opts.can_user = &sc;
    } else if (strncmp(can, "socketcan:", 10) == 0 && can[10] != '\0') {
      if (sc.can_faults.on) {
        fprintf(stderr,
                "fluxdrive-sil: %s: inject.can: only with --can socketcand:PORT (the SIL's "
                "own CAN server)\n",
                scenario);
        return 2;
      }
      if (can_socketcan_open(&sck, can + 10, err, sizeof err) != 0) {
        fprintf(stderr, "fluxdrive-sil: --can %s: %s\n", can, err);
        return 2;
      }
      opts.can_io = io_socketcan;
    } else {
      fprintf(stderr, "fluxdrive-sil: --can: expected socketcand:PORT or socketcan:IFACE\n");
      return 2;
    }
  }
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
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
  int r = sil_run_ex(&sc, &opts, obs, obs_user, &res, err, sizeof err);
  if (can != NULL) {
    fprintf(stderr,
            "fluxdrive-sil: CAN: %u frames read, %u ok, %u rejected, %u ignored, %u TX dropped, "
            "%u timeouts\n",
            (unsigned)res.can.rx_frames, (unsigned)res.can.rx_ok, (unsigned)res.can.rx_errors,
            (unsigned)res.can.rx_ignored, (unsigned)res.can.tx_dropped, (unsigned)res.can.timeouts);
    if (sc.can_faults.on) {
      fprintf(stderr,
              "fluxdrive-sil: CAN link (inject.can): rx %u of %u frames lost, %u delayed; "
              "tx %u of %u lost, %u delayed\n",
              (unsigned)scd.rx.lost, (unsigned)scd.rx.offered, (unsigned)scd.rx.delayed,
              (unsigned)scd.tx.lost, (unsigned)scd.tx.offered, (unsigned)scd.tx.delayed);
    }
    can_socketcand_close(&scd);
    can_socketcan_close(&sck);
  }
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
