#!/usr/bin/env bash
# Runs the libFuzzer targets built in build-san/ (make fuzz-build) for SECONDS each, FUZZ_JOBS of them at
# a time (default: the number of cores; each target is one libFuzzer worker): make fuzz-smoke runs it
# with 60 s, make fuzz FUZZ_SECONDS=N with N. New inputs go to
# build-san/corpus/<target>/ (the committed seeds in fuzz/corpus/<target>/ are only read); a crash,
# leak, timeout or out-of-memory input is written to build-san/artifacts/<target>/ and fails the run.
# Usage: [FUZZ_SEED=N] fuzz/run.sh SECONDS [TARGET...]   (targets: scene vdb cli mesh; default all)
# FUZZ_SEED: libFuzzer's -seed (default 0: a random seed); make fuzz-smoke passes 1 so that CI repeats the
# same mutations from run to run (fork-mode job timing still varies), make fuzz leaves it random.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:?usage: fuzz/run.sh SECONDS [TARGET...]}
shift
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scene vdb cli mesh)
BUILD_FUZZ=${BUILD_FUZZ:-build-san}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
jobs=${FUZZ_JOBS:-$(nproc)}
for t in "${targets[@]}"; do
  bin="$BUILD_FUZZ/bin/${t}_fuzz"
  [ -x "$bin" ] || { echo "fuzz/run.sh: $bin not built (make fuzz-build)" >&2; exit 1; }
done

# Fuzzes one target; its summary lines go to stderr prefixed with the target's name, its whole log to
# $BUILD_FUZZ/<target>.log. Returns non-zero on a finding.
fuzz_one() {
  local t=$1 bin="$BUILD_FUZZ/bin/${1}_fuzz"
  local asan=$ASAN_OPTIONS max_len timeout status
  local extra=()
  case $t in
    # The uncompressed NanoVDB seed is ~310 KB. vdb_fuzz replaces operator new (see the file), so
    # memory from a library's operator new may come back through its free(): not a finding.
    # OpenVDB 10.0 itself overflows a heap buffer on some corrupt .vdb files (docs/reliability.md), so
    # this target runs in fork mode and keeps going past crashes; fuzz/triage.sh then replays every
    # saved input and fails only on those whose fault lies outside libopenvdb.so.
    # -detect_leaks=0: OpenVDB leaks on most corrupt .vdb files (suppressed), and libFuzzer's leak
    # check after each such input scanned the whole heap (about 1 s): 1-30 inputs/s. LeakSanitizer
    # still runs when each fork-mode job exits, so a leak in nimbus still fails that job.
    # -timeout=30: a valid grid with a bbox near the 2^31-voxel limit takes ~0.2 s to analyse in a
    # Release build and over 10 s under ASan, UBSan and coverage instrumentation.
    vdb) max_len=400000; asan=$asan:alloc_dealloc_mismatch=0; timeout=30
         extra=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 -detect_leaks=0) ;;
    *) max_len=4096; timeout=10 ;;  # scene, cli, mesh (OBJ text)
  esac
  local dict=()
  [ -f "fuzz/$t.dict" ] && dict=(-dict="fuzz/$t.dict")
  mkdir -p "$BUILD_FUZZ/corpus/$t" "$BUILD_FUZZ/artifacts/$t"
  echo "fuzz/run.sh: $t for ${seconds}s" >&2
  # One worker; -timeout: one input over 10 s (vdb: 30 s) is a hang; -rss_limit_mb: memory over
  # 2 GiB is a bug (a malloc above it, too).
  # The fuzzer's own exit status decides (PIPESTATUS[0], read in the branch: a `|| true` after the
  # pipeline would replace it with true's).
  if ASAN_OPTIONS=$asan "$bin" "$BUILD_FUZZ/corpus/$t" "fuzz/corpus/$t" "${dict[@]}" "${extra[@]}" -max_total_time="$seconds" -seed="${FUZZ_SEED:-0}" \
    -timeout="$timeout" -rss_limit_mb=2048 -max_len="$max_len" -print_final_stats=1 \
    -artifact_prefix="$BUILD_FUZZ/artifacts/$t/" 2>&1 | tee "$BUILD_FUZZ/$t.log" | \
    grep -E '^(#[0-9]+.*(INITED|DONE|pulse))|^#[0-9]+: cov|stat::|ERROR|SUMMARY|Test unit written|^==|^INFO: (fuzzed|exiting)|^Done' | \
    sed "s/^/[$t] /" >&2; then
    status=0
  else
    status=${PIPESTATUS[0]}
  fi
  if [ ${#extra[@]} -gt 0 ]; then  # fork mode: the saved inputs decide
    status=0
    grep -q 'INFO: fuzzed for' "$BUILD_FUZZ/$t.log" || status=1  # not anchored: a forked job's output may end without a newline just before it
    FUZZ_TIMEOUT=$timeout fuzz/triage.sh "$t" >&2 || status=1
  fi
  if [ "$status" -ne 0 ]; then
    echo "fuzz/run.sh: $t FAILED (exit $status); see $BUILD_FUZZ/$t.log and $BUILD_FUZZ/artifacts/$t/" >&2
    return 1
  fi
}

# At most $jobs targets at once; every target runs to its end, and the run fails if any of them found
# something.
failed=0
pids=()
names=()
for t in "${targets[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do sleep 1; done
  fuzz_one "$t" &
  pids+=($!)
  names+=("$t")
done
for i in "${!pids[@]}"; do
  wait "${pids[$i]}" || { failed=1; echo "fuzz/run.sh: ${names[$i]} failed" >&2; }
done
exit $failed
