#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# tools/run_fuzzers.sh SECONDS JOBS — every libFuzzer target in build-asan/tests/fuzz for SECONDS
# each, JOBS at a time (a fuzzer is one process on one core: two at a time on this 2-core
# machine take half the wall time for the same executions each). Corpora persist in
# build-asan/fuzz-corpus/<name>, logs in build-asan/<name>.log (tools/check_tests_ran.py reads
# them). A finding or a crash prints the log's tail and fails.
set -e
secs=${1:?seconds}
jobs=${2:-2}
export FUZZ_SECONDS="$secs"
for f in build-asan/tests/fuzz/fuzz_*; do
  [ -x "$f" ] && echo "$f"
done | xargs -P "$jobs" -n 1 sh -c '
  f=$1; n=$(basename "$f"); mkdir -p build-asan/fuzz-corpus/$n
  echo "fuzz: $n for $FUZZ_SECONDS s"
  if ! "$f" -max_total_time=$FUZZ_SECONDS -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
      build-asan/fuzz-corpus/$n 2>build-asan/$n.log; then
    echo "fuzz: $n failed:"; tail -40 build-asan/$n.log; exit 255
  fi
  echo "fuzz: $n: $(grep -E "^(Done|stat::number_of_executed_units)" build-asan/$n.log | tail -1)"
' sh
