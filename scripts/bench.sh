#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Every benchmark in one command (`make bench` runs it): installs the peers (Debian packages),
# builds, runs SIM against iceoryx, Fast DDS and Cyclone DDS on the SIM paper's workloads and
# writes the Markdown table, the CSV/JSON and the plots into bench/results/; then the driver
# benchmarks (Hesai decode, cut-to-reader and live CPU; camera decode paths) into
# bench/results/{hesai,camera}.txt.
#
#   scripts/bench.sh [--no-install] [--quick] [-- extra sim_bench options, e.g. --runs 3 --cpu 0,1]
#
# Environment: SIM_BENCH_BUILD (build folder, default build-bench), SIM_BENCH_OUT (results folder,
# default bench/results). Exit codes: 0 all ran, 1 a step failed, 2 usage error.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${SIM_BENCH_BUILD:-$root/build-bench}
out=${SIM_BENCH_OUT:-$root/bench/results}
install=1
quick=0
extra=()

while [ $# -gt 0 ]; do
  case "$1" in
    --no-install) install=0 ;;
    --quick) quick=1 ;;
    -h|--help) sed -n '3,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "bench.sh: unknown option '$1': see scripts/bench.sh --help." >&2; exit 2 ;;
  esac
  shift
done

step() { printf '\n== %s\n' "$*" >&2; }

if [ "$install" = 1 ]; then
  step "Installing the build tools and the peers (scripts/deps/*.txt)"
  packages=$(grep -hv '^\s*#' "$root"/scripts/deps/*.txt | sed 's/\s*#.*//' | grep -v '^\s*$' | sort -u)
  if [ "$(id -u)" = 0 ]; then
    # shellcheck disable=SC2086
    apt-get install -y --no-install-recommends $packages
  elif command -v sudo >/dev/null; then
    # shellcheck disable=SC2086
    sudo apt-get install -y --no-install-recommends $packages
  else
    echo "bench.sh: not root and no sudo: install these, then rerun with --no-install:" >&2
    echo "$packages" | tr '\n' ' ' >&2
    echo >&2
    exit 1
  fi
fi

step "Building sim_bench in $build"
cmake -S "$root" -B "$build" -DSIM_BUILD_BENCH=ON -DSIM_BUILD_TESTS=OFF \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$build" --target sim_bench -j"$(nproc)"
drivers=(bench_hesai_decode bench_hesai_live bench_camera_decode)
cmake --build "$build" --target "${drivers[@]}" -j"$(nproc)"
bench="$build/bench/transport/sim_bench"

mkdir -p "$out"
if [ "$quick" = 1 ]; then
  args=(--quick --skip-missing --csv "$out/transport_quick.csv")
else
  args=(--transports sim-poll,sim-block,sim-zero,iceoryx,fastdds,cyclone
        --payloads 25920,1382400,921600,6912000 --readers 1,10 --rate 100
        --frames 1100 --warmup 100 --runs 5 --csv "$out/transport.csv")
fi
args+=("${extra[@]}")

step "Running: sim_bench ${args[*]}"
status=0
"$bench" "${args[@]}" || status=$?

csv="$out/transport.csv"
[ "$quick" = 1 ] && csv="$out/transport_quick.csv"
step "Writing the report next to $csv"
# Debian's python3 has Debian's matplotlib; a pyenv or venv python3 first on PATH may not.
python=/usr/bin/python3
[ -x "$python" ] || python=python3
"$python" "$root/bench/transport/report.py" "$csv" \
  --title "SIM transport benchmark ($(uname -m), $(nproc) CPUs, $(date -u +%Y-%m-%d))" \
  --command "sim_bench ${args[*]}" || status=1

min_time=1
live=(--seconds 20 --revolutions 300)
if [ "$quick" = 1 ]; then min_time=0.05; live=(--seconds 2 --revolutions 20); fi
step "Hesai: decode throughput, cut to reader, live driver CPU -> $out/hesai.txt"
{ "$build/bench/hesai/bench_hesai_decode" --benchmark_min_time="$min_time" &&
  "$build/bench/hesai/bench_hesai_live" "${live[@]}"; } 2>&1 | tee "$out/hesai.txt" || status=1
step "Camera: decode paths into the slot against OpenCV -> $out/camera.txt"
"$build/bench/camera/bench_camera_decode" --benchmark_min_time="$min_time" 2>&1 |
  tee "$out/camera.txt" || status=1
exit "$status"
