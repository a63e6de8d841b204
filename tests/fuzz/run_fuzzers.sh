#!/usr/bin/env bash
# `make fuzz`: runs each harness for $FUZZ_SECONDS (default 60) seconds, one
# after the other, and prints executions and coverage per harness.
# Usage: run_fuzzers.sh <fuzz build folder> <python> "<C++ harnesses>" "<Python harnesses>"
#
# Each run starts from tests/fuzz/<name>/corpus plus its crashers; what it
# finds new goes to a scratch folder and is merged back into the corpus
# minimized (-merge=1: only inputs that add coverage). A crash stops that
# harness and leaves the input in tests/fuzz/<name>/crashers/ as crash-<sha1>:
# fix the cause, rename the file to say what it was, commit it. The summary
# lines ("fuzz-summary") go to $logs/fuzz-summary.txt, and fuzz_table.py
# turns them into the table docs/reliability.md links to ($FUZZ_TABLE,
# default docs/reliability-fuzz.md).
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$1 python=$2 cpp_harnesses=$3 python_harnesses=$4
seconds=${FUZZ_SECONDS:-60}
logs=${FUZZ_LOGS:-$build/fuzz-logs}
table=${FUZZ_TABLE:-$(cd "$here/../.." && pwd)/docs/reliability-fuzz.md}
mkdir -p "$logs"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
command -v llvm-symbolizer-14 > /dev/null && export ASAN_SYMBOLIZER_PATH=$(command -v llvm-symbolizer-14)
status=0
summary=()

run() {  # name, command...: fuzz, merge, summarize
  local name=$1 dir=$2; shift 2
  local work
  work=$(mktemp -d)
  mkdir -p "$dir/crashers"
  local before
  before=$(ls "$dir/corpus" | wc -l)
  echo "== fuzzing $name for ${seconds}s"
  local start=$SECONDS  # a crash ends the run early: the summary gives the time it really ran
  "$@" -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=60 -print_final_stats=1 \
    -artifact_prefix="$dir/crashers/" "$work" "$dir/corpus" "$dir/crashers" > "$logs/$name.log" 2>&1
  local rc=$? took=$((SECONDS - start))
  local execs cov
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$logs/$name.log" | tail -n 1)
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$logs/$name.log" | tail -n 1)
  local result=clean
  if [ $rc -ne 0 ]; then
    result="CRASH (see $logs/$name.log and $dir/crashers/)"
    status=1
    tail -n 40 "$logs/$name.log"
  fi
  # Merge what is new into the corpus, minimized.
  "$@" -merge=1 "$dir/corpus" "$work" > "$logs/$name.merge.log" 2>&1 || true
  rm -rf "$work"
  local after
  after=$(ls "$dir/corpus" | wc -l)
  summary+=("fuzz-summary $name: ${execs:-0} executions in ${took}s, ${cov:-cov: ? ft: ?}, corpus $after files (+$((after - before))), $result, $(date -u +%F)")
}

for name in $cpp_harnesses; do
  run "$name" "$here/$name" "$build/tests/fuzz/fuzz_$name"
done
for name in $python_harnesses; do
  run "$name" "$here/python/$name" "$python" "$here/python/fuzz_$name.py"
done
printf '%s\n' "${summary[@]}" | tee "$logs/fuzz-summary.txt"
"$python" "$here/fuzz_table.py" "$logs/fuzz-summary.txt" "$table" && echo "fuzz table: $table"
exit $status
