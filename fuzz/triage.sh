#!/usr/bin/env bash
# Replays every input a fuzz target saved under build-san/artifacts/TARGET/ and sorts it by the first
# stack frame that is not the sanitizer, libFuzzer, libc or libstdc++: inside libopenvdb.so is a
# third-party OpenVDB 10.0 defect (docs/reliability.md lists the known ones), anything else is a
# nimbus bug and makes this script exit 1.
# Usage: [FUZZ_TIMEOUT=SECONDS] fuzz/triage.sh TARGET   (replay time limit, default 10; run.sh passes 30 for vdb)
set -uo pipefail
cd "$(dirname "$0")/.."
t=${1:?usage: fuzz/triage.sh TARGET}
BUILD_FUZZ=${BUILD_FUZZ:-build-san}
export ASAN_OPTIONS=detect_leaks=1:alloc_dealloc_mismatch=0
export LSAN_OPTIONS=suppressions=$PWD/fuzz/lsan.supp
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ours=0
n=0
for f in "$BUILD_FUZZ"/artifacts/"$t"/*; do
  [ -f "$f" ] || continue
  n=$((n + 1))
  log=$("$BUILD_FUZZ/bin/${t}_fuzz" -timeout="${FUZZ_TIMEOUT:-10}" -rss_limit_mb=2048 "$f" 2>&1)
  if ! grep -qE 'ERROR|SUMMARY|libFuzzer: timeout' <<<"$log"; then
    echo "fixed (replays cleanly): $f"
    continue
  fi
  kind=$(grep -m1 -oE 'SUMMARY: [A-Za-z]+: [a-z-]+|libFuzzer: timeout' <<<"$log")
  frame=$(grep -E '^ +#[0-9]+ ' <<<"$log" |
          grep -vE 'fuzzer::|__sanitizer|__asan|__interceptor|__ubsan|libc\.so|libstdc\+\+\.so|libgcc_s|operator (new|delete)|in (malloc|calloc|realloc|free) ' |
          head -1 | sed -E 's/^ +#[0-9]+ 0x[0-9a-f]+ (in )?//' | cut -c1-160)
  case $frame in
    *libopenvdb.so*|*/usr/include/openvdb/*) echo "third-party OpenVDB ($kind): $f: $frame" ;;
    *) echo "NIMBUS ($kind): $f: $frame"; ours=1 ;;
  esac
done
echo "fuzz/triage.sh: $t: $n saved inputs" >&2
exit $ours
