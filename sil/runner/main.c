/*
 * main.c - fluxdrive-sil: run one scenario.
 *
 *   fluxdrive-sil SCENARIO.json [options]     (fluxdrive-sil --help: the options)
 *
 * The options are one table (`options` below: name, argument, help,
 * handler); --help is printed from it.
 * --preempt runs the scenario's plant and drive with the ISR preempting the
 * main loop at random points (sil/runner/sil_preempt.h; at most 600 s of
 * wall time) and prints the result (JSON); exit code 3 when an invariant
 * was violated. --record-isr records every ISR's inputs and outputs for
 * the PIL replay (sil/runner/isr_record.h, docs/pil.md).
 * --can socketcand:PORT | socketcan:IFACE: the drive is commanded over CAN
 * (docs/can.md) and the scenario's references are not applied. socketcand
 * listens on 127.0.0.1:PORT (0: a free port, printed on stderr); the
 * simulation starts when the first client is in raw mode. --realtime paces
 * the simulation to the wall clock (interactive use, the CAN tests);
 * without it the simulation runs as fast as it can and all CAN times
 * (timestamps, timeout) are simulated time.
 * SIGINT/SIGTERM end the run early (the summary is still printed).
 * Exit codes: 0 ran (faults are results, reported in the summary),
 * 1 I/O error, 2 bad scenario or usage.
 */
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_proto.h"
#include "can_socketcan.h"
#include "can_socketcand.h"
#include "isr_record.h"
#include "log_npy.h"
#include "scenario.h"
#include "scenario_params.h"
#include "scenario_keys.h"
#include "sil_preempt.h"
#include "signals_json.h"
#include "sil_run.h"
#include "summary.h"
#include "truth.h"

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

/* What the command line asks for. */
typedef struct {
  const char *scenario, *log_path, *summary_path, *record_path, *dump_path, *can;
  const char *keys_doc, *keys_doc_write, *params_path;
  int bench, print_config, print_params, print_signals, realtime, keys, help, print_truth;
  long decimate, preempt_n, seed, node, can_timeout, max_gap_us;
} cli_t;

/* An option: its handler stores into the cli_t field at `at` (a path, a
 * flag set to 1, or an integer in [lo, hi]). */
typedef struct option option_t;
struct option {
  const char *name;
  const char *arg; /* the argument's name, NULL for a flag */
  const char *help;
  int (*handler)(cli_t *o, const option_t *op, const char *arg); /* 0, or -1: usage error */
  size_t at;
  long lo, hi;
};

static int set_path(cli_t *o, const option_t *op, const char *arg) {
  *(const char **)(void *)((char *)o + op->at) = arg;
  return 0;
}

static int set_flag(cli_t *o, const option_t *op, const char *arg) {
  (void)arg;
  *(int *)(void *)((char *)o + op->at) = 1;
  return 0;
}

static int set_long(cli_t *o, const option_t *op, const char *arg) {
  return parse_long(op->name, arg, op->lo, op->hi, (long *)(void *)((char *)o + op->at));
}

#define PATH(f)         set_path, offsetof(cli_t, f), 0, 0
#define FLAG(f)         set_flag, offsetof(cli_t, f), 0, 0
#define LONG(f, lo, hi) set_long, offsetof(cli_t, f), (lo), (hi)
static const option_t options[] = {
    {"--log", "PATH.npy", "write the log (docs/log-format.md)", PATH(log_path)},
    {"--params", "FILE.json",
     "the drive's parameters from a parameter file (a commissioning's), the plant keeping the "
     "scenario's machine (default: $FLUXDRIVE_PARAMS if set; docs/commissioning.md)",
     PATH(params_path)},
    {"--summary", "PATH.json", "write the summary too (it is printed)", PATH(summary_path)},
    {"--decimate", "N", "log every N-th period (overrides log.decimation)",
     LONG(decimate, 1, 1000000)},
    {"--bench", NULL, "no log; print steps, wall time and the real-time factor", FLAG(bench)},
    {"--print-config", NULL, "print the resolved parameters (JSON) and exit", FLAG(print_config)},
    {"--print-truth", NULL,
     "print the plant's true values a commissioning identifies (JSON, truth.h) and exit",
     FLAG(print_truth)},
    {"--print-params", NULL, "print the parameter table (JSON; no scenario needed) and exit",
     FLAG(print_params)},
    {"--print-signals", NULL,
     "print the signal tables (log columns, CAN signals, PIL fields: JSON; no scenario needed, "
     "signals_json.h) and exit",
     FLAG(print_signals)},
    {"--dump-scenario", "PATH", "write the parsed scenario's bytes (scripts/scenario_equiv.py)",
     PATH(dump_path)},
    {"--record-isr", "PATH.bin", "record every ISR for the PIL replay (docs/pil.md)",
     PATH(record_path)},
    {"--realtime", NULL, "pace the simulation to the wall clock", FLAG(realtime)},
    {"--preempt", "PERIODS", "race check: the ISR preempts the main loop at random points",
     LONG(preempt_n, 1, 100000000)},
    {"--seed", "N", "--preempt: the interrupt times' seed", LONG(seed, 0, 0x7fffffff)},
    {"--max-gap-us", "U", "--preempt: at most U us between interrupts",
     LONG(max_gap_us, 1, 100000)},
    {"--can", "SPEC", "socketcand:PORT or socketcan:IFACE: the drive over CAN (docs/can.md)",
     PATH(can)},
    {"--node", "N", "--can: the drive's node id", LONG(node, 0, CAN_NODE_MAX)},
    {"--can-timeout", "MS", "--can: the command timeout", LONG(can_timeout, 0, 60000)},
    {"--keys", NULL, "print the scenario key reference (Markdown) and exit", FLAG(keys)},
    {"--keys-doc", "DOC.md", "check DOC.md's scenario key reference against the table",
     PATH(keys_doc)},
    {"--keys-doc-write", "DOC.md", "write it into DOC.md", PATH(keys_doc_write)},
    {"--help", NULL, "this help", FLAG(help)},
};

static int usage(FILE *f, int code) {
  fprintf(f, "usage: fluxdrive-sil SCENARIO.json [options]\n");
  for (size_t i = 0; i < sizeof options / sizeof options[0]; ++i) {
    char left[64];
    snprintf(left, sizeof left, "%s%s%s", options[i].name, options[i].arg ? " " : "",
             options[i].arg ? options[i].arg : "");
    fprintf(f, "  %-24s %s\n", left, options[i].help);
  }
  return code;
}

/* The command line into o; 0, or -1 on a usage error (reported). */
static int parse_cli(int argc, char **argv, cli_t *o) {
  for (int i = 1; i < argc; ++i) {
    const option_t *op = NULL;
    for (size_t k = 0; k < sizeof options / sizeof options[0] && op == NULL; ++k) {
      op = strcmp(argv[i], options[k].name) == 0 ? &options[k] : NULL;
    }
    if (op != NULL && (op->arg == NULL || i + 1 < argc)) {
      if (op->handler(o, op, op->arg != NULL ? argv[++i] : NULL) != 0) {
        return -1;
      }
    } else if (argv[i][0] == '-' || o->scenario != NULL) {
      usage(stderr, 2);
      return -1;
    } else {
      o->scenario = argv[i];
    }
  }
  return 0;
}

int main(int argc, char **argv) {
  cli_t cli = {.max_gap_us = 20, .seed = 1, .node = -1, .can_timeout = -1};
  if (parse_cli(argc, argv, &cli) != 0) {
    return 2;
  }
  if (cli.help) {
    return usage(stdout, 0);
  }
  if (cli.keys) {
    char *md = scenario_keys_markdown();
    if (md == NULL) {
      return 1;
    }
    fputs(md, stdout);
    free(md);
    return 0;
  }
  if (cli.keys_doc != NULL || cli.keys_doc_write != NULL) {
    char msg[600];
    const int w = cli.keys_doc_write != NULL;
    const int r = scenario_keys_doc(w ? cli.keys_doc_write : cli.keys_doc, w, msg, sizeof msg);
    if (r != 0) {
      fprintf(stderr, "fluxdrive-sil: %s\n", msg);
    }
    return r == 0 ? 0 : 1;
  }
  const char *const scenario = cli.scenario, *const log_path = cli.log_path;
  const char *const summary_path = cli.summary_path, *const record_path = cli.record_path;
  const char *const can = cli.can;
  if (cli.print_params || cli.print_signals) {
    char *js = cli.print_params ? params_json() : signals_json();
    if (js == NULL) {
      return 1;
    }
    printf("%s\n", js);
    free(js);
    return 0;
  }
  if (scenario == NULL) {
    return usage(stderr, 2);
  }
  static scenario_t sc;
  char err[512];
  if (scenario_load_file(scenario, &sc, err, sizeof err) != 0) {
    fprintf(stderr, "fluxdrive-sil: %s\n", err);
    return 2;
  }
  const char *params = cli.params_path != NULL ? cli.params_path : getenv("FLUXDRIVE_PARAMS");
  if (params != NULL && params[0] != '\0') {
    if (scenario_apply_params(&sc, params, err, sizeof err) != 0) {
      fprintf(stderr, "fluxdrive-sil: %s\n", err);
      return 2;
    }
    fprintf(stderr, "fluxdrive-sil: the drive's parameters from %s\n", params);
  }
  if (cli.dump_path != NULL) {
    if (scenario_dump(&sc, cli.dump_path) != 0) {
      fprintf(stderr, "fluxdrive-sil: %s: cannot write the dump\n", cli.dump_path);
      return 1;
    }
    return 0;
  }
  if (cli.print_config) {
    char *js = config_json(&sc);
    if (js == NULL) {
      return 1;
    }
    printf("%s\n", js);
    free(js);
    return 0;
  }
  if (cli.print_truth) {
    char *js = truth_json(&sc);
    if (js == NULL) {
      return 1;
    }
    printf("%s\n", js);
    free(js);
    return 0;
  }
  if (cli.preempt_n > 0) {
    const sil_preempt_opts_t po = {(uint64_t)cli.preempt_n, 600.0, (uint32_t)cli.seed,
                                   (double)cli.max_gap_us};
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
  if (cli.decimate > 0) {
    sc.log_decimation = (int)cli.decimate;
  }
  sil_opts_t opts = {0};
  can_proto_cfg_t pcfg;
  can_proto_cfg_default(&pcfg);
  if (cli.node >= 0) {
    pcfg.node = (uint8_t)cli.node;
  }
  if (cli.can_timeout >= 0) {
    pcfg.timeout_ms = (uint16_t)cli.can_timeout;
  }
  opts.realtime = cli.realtime != 0;
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
  int logging = log_path != NULL && !cli.bench;
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
  if (cli.bench) {
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
