#!/usr/bin/env bash
# Where a build's time went, from Ninja's log: the CPU-seconds of every step (compile, link,
# precompiled header) summed, and the heaviest steps. Time summed over steps, not wall time: on a
# shared machine it is the number that compares two builds (docs/build-times.md).
#
#   scripts/build-times.sh [BUILD_DIR] [N]     default build/release, the 25 heaviest steps
#   SIM_SINCE=<ms> scripts/build-times.sh …    only steps that started after <ms> of the log
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
echo "heaviest $top:"
head -n "$top" "$build/.build-times" | awk '{ printf "%8.1f s  %s\n", $1 / 1000, $2 }'
