#!/usr/bin/env bash
# PIL test (docs/pil.md): cross-builds the PIL image (preset cortex-m4f, the
# board's MinSizeRel flags, -Werror) into BUILD_DIR, then `fluxdrive pil`
# replays the two PIL scenarios with every law (and FOC on the flux-map
# machine syr_1k1) on QEMU mps2-an386 and traces
# every ISR of both (--isrs all: the whole flux-weakening ramp, current
# limit, voltage limit and MTPV included). Outputs must agree with this host
# build's within the stated tolerance. FOC, PI-DFVC and DB-DFVC meet issue
# 24 point 8's limits (mean <= 2000, worst <= 2300 instructions; measured
# on the ramp 1340 / 1682, 1963 / 2286 and 1983 / 2297, on the torque step
# 1331 / 1608, 1941 / 2244 and 1951 / 2255): checked as such, and the
# DB-DFVC worst case at or below 50 % of the 10625-cycle budget in
# estimated Cortex-M4 cycles (measured 38 %; why 50 %: docs/pil.md,
# "Scenarios and checks"). Prints the reports and
# writes their markdown sections to BUILD_DIR/benchmarks-foc.md and
# BUILD_DIR/benchmarks.md.
# Usage: run_pil.sh SRC_DIR BUILD_DIR PYTHON FLUXDRIVE_SIL
set -euo pipefail
src=$1
build=$2
python=$3
sil=$4
cmake --preset cortex-m4f -S "$src" -B "$build/cross" >/dev/null
cmake --build "$build/cross" --target fluxdrive-pil.elf fluxdrive-g474.elf
cd "$build"
# the tools of the tree under test, whatever the venv's editable install points to
export PYTHONPATH="$src/tools/src${PYTHONPATH:+:$PYTHONPATH}"
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_torque_step.json" \
  "$src/sil/scenarios/pil_fw_ramp.json" --law foc --isrs all \
  --sil "$sil" --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks-foc.md" --check-mean 2000 --check-worst-all 2300
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_torque_step.json" \
  "$src/sil/scenarios/pil_fw_ramp.json" --law pi_dfvc,db_dfvc --isrs all \
  --sil "$sil" --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks.md" --check-mean 2000 --check-worst-all 2300 \
  --check-worst 2300 --check-cycles 50
# FOC on the saturated syr_1k1 (flux map in the stream): agreement, counts,
# calls and instructions per call of the map lookup and the incremental
# inductance (docs/benchmarks.md, "Flux maps").
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_syr_foc.json" --law foc --isrs all \
  --functions --sil "$sil" --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks-map.md"
# the decoupled DFVC of Varatharajan 2022 on the same map through MTPA,
# flux weakening and the MTPV limit: agreement, and issue 24 point 8's
# target of at most 2100 instructions per ISR on average (measured 2062,
# worst 2432: docs/benchmarks.md, "Decoupled DFVC")
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_dfvc_decoupled.json" --law dfvc_decoupled \
  --isrs all --check-mean 2100 --sil "$sil" --elf "$build/cross/pil/fluxdrive-pil.elf" \
  --out "$build/work" --markdown "$build/benchmarks-decoupled.md"
# sensorless FOC on the star-point position (Fabbri 2022): the DFC window,
# signals with the sequentiality compensation, one IVD iteration, the Q31
# CORDIC atan2 and the PLL from standstill (alignment) to 500 rpm:
# agreement, and the goal of at most 90 instructions per IVD
# iteration (measured 62: docs/benchmarks.md, "Star-point position")
# Issue 24 point 8's board target for the three star-point sources: the
# estimated board worst case (PIL worst ISR, board HAL and ISR wrapper, the
# core's trigonometry on the G474's CORDIC: `fluxdrive pil --board-elf`,
# docs/pil.md) at most 45 % of the budget, checked on all three
# (--check-board 45; measured DFC-IVD 42.1 %, IVD + KF + RLS 44.5 %, the
# EKF 44.9 %, their worst the speed loop's ISRs: docs/benchmarks.md,
# "Sensorless chain")
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_dfc_ivd.json" --law foc --isrs all \
  --functions --check-call dfc_ivd_step=90 --check-board 45 \
  --board-elf "$build/cross/boards/stm32g4/fluxdrive-g474.elf" --sil "$sil" \
  --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks-dfc.md"
# the sensorless drive of Fabbri 2022 chapter 4: IVD on the RLS's a, b and
# the Kalman filter on speed, angle and load torque under FOC, from
# standstill to 500 rpm: agreement, the goals per call (KF: predict
# + update <= 360, RLS <= 220; measured 158 and 146) and for the whole ISR:
# issue 24 point 8's software mean < 2600 (measured 2322) and, with the
# core's trigonometry on the STM32G474's CORDIC co-processor, < 2300, the
# issue's target (measured 2257: docs/benchmarks.md, "Sensorless chain:
# Kalman filter, EKF, RLS"); then the EKF (<= 790; measured 251)
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_ivd_kf_rls.json" --law foc --isrs all \
  --functions --check-call kf_mech_predict=100 --check-call kf_mech_update=260 \
  --check-call rls_ab_update=220 --check-mean 2600 --check-mean-cordic 2300 --check-board 45 \
  --board-elf "$build/cross/boards/stm32g4/fluxdrive-g474.elf" --sil "$sil" \
  --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks-kf.md"
"$python" -m fluxdrive pil "$src/sil/scenarios/pil_ekf.json" --law foc --isrs all \
  --functions --check-call kf_mech_predict=100 --check-call kf_mech_update_ekf=690 \
  --check-board 45 --board-elf "$build/cross/boards/stm32g4/fluxdrive-g474.elf" \
  --sil "$sil" --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks-ekf.md"
# Issue 25: each identification procedure's ISR cost (docs/pil.md,
# "Identification procedures"). One scenario per procedure (rs and ldq in
# one), each run as `fluxdrive commission` runs it: the offsets, then the
# procedure, the drive disabled. Every ISR is replayed and compared (the
# identification request in the stream); the ISRs are grouped by the
# host's procedure (--procs) and traced in windows (--sample 64: of each
# procedure's run its first and last 64 ISRs and 64 around each change of
# its phase, where the fits and hand-overs run; 5.7k of 207k ISRs, the
# whole runs traced take about 15 min: docs/pil.md gives those figures).
# The laws' targets of issue 24 point 8, per procedure: mean <= 2000 and
# worst <= 2300 instructions, board worst case <= 45 % of the budget
# (the sample's mean is its windows', not the run's). Not met yet, held
# from growing (--proc-limit): star (mean 2367, worst 3276, 54 %: the
# DFC position source every period, the sweep's fit at its end). ldq's
# least squares runs over the periods after each axis' measurement (worst
# 1880 instructions, 37.6 %; 4477, 81 % when it was one ISR).
S="$src/sil/scenarios"
"$python" -m fluxdrive pil "$S/pil_ident_rl.json" "$S/pil_ident_fmap.json" \
  "$S/pil_ident_star.json" "$S/pil_ident_poles.json" "$S/pil_ident_enc.json" \
  "$S/pil_ident_flux.json" "$S/pil_ident_mech.json" --procs --sample 64 \
  --check-mean 2000 --check-worst-all 2300 --check-board 45 \
  --proc-limit star=2400,3300,55 \
  --board-elf "$build/cross/boards/stm32g4/fluxdrive-g474.elf" --sil "$sil" \
  --elf "$build/cross/pil/fluxdrive-pil.elf" --out "$build/work" \
  --markdown "$build/benchmarks-ident.md"
