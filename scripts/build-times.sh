#!/usr/bin/env bash
# Where a build's time went, from Ninja's log: the CPU-seconds of every step (compile, link,
# precompiled header) summed, and the heaviest steps. Time summed over steps, not wall time: on a
# shared machine it is the number that compares two builds (docs/build-times.md).
#
#   scripts/build-times.sh [BUILD_DIR] [N]     default build/release, the 25 heaviest steps
#   SIM_SINCE=<ms> scripts/build-times.sh …    only steps that started after <ms> of the log
# It also sums the compiles that include CLI11 (from Ninja's recorded dependencies): header-only,
# about 10 CPU-s per translation unit that includes it, kept out of headers (docs/build-times.md).
set -euo pipefail
build=${1:-build/release}
top=${2:-25}
log=$build/.ninja_log
[[ -f $log ]] || { echo "build-times: no $log (configure with -G Ninja and build first)" >&2; exit 2; }
# .ninja_log v5: start end mtime output hash (ms). The newest entry of each output counts.
awk -v since="${SIM_SINCE:-0}" -F'\t' 'NR > 1 && $1 >= since { d[$4] = $2 - $1 }
  END { for (o in d) print d[o], o }' "$log" | sort -rn >"$build/.build-times"
awk '{ kind = "other"
       if ($2 ~ /\.(gch|pch)$/) kind = "precompiled headers"
       else if ($2 ~ /\.o$/) kind = "compiles"
       else if ($2 ~ /\.a$/) kind = "archives"
       else kind = "links"
       s[kind] += $1; n[kind]++; t += $1 }
     END { for (k in s) printf "%-20s %4d steps %8.1f s\n", k, n[k], s[k] / 1000
           printf "%-20s %4d steps %8.1f s\n", "total", NR, t / 1000 }' "$build/.build-times"
# Objects whose recorded dependencies include CLI11, then their share of the sum.
if command -v ninja >/dev/null; then
  ninja -C "$build" -t deps 2>/dev/null |
    awk '/^[^ \t].*: #deps/ { o = $1; sub(/:$/, "", o) } /\/CLI\/CLI\.hpp$/ { print o }' |
    sort -u >"$build/.build-times-cli11"
  awk 'NR == FNR { cli[$1] = 1; next } { t += $1 } ($2 in cli) { s += $1; n++ }
       END { printf "%-20s %4d steps %8.1f s  (%.0f%% of the total)\n", "include CLI11", n, s / 1000,
                    (t > 0 ? 100 * s / t : 0) }' "$build/.build-times-cli11" "$build/.build-times"
fi
echo "heaviest $top:"
head -n "$top" "$build/.build-times" | awk '{ printf "%8.1f s  %s\n", $1 / 1000, $2 }'
