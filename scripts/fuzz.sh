#!/usr/bin/env bash
# Fuzzing and sanitizers: builds the libFuzzer targets and the C++ tests with AddressSanitizer
# and UndefinedBehaviorSanitizer (clang, in build-fuzz/), then runs each fuzz target.
#
#   bash scripts/fuzz.sh                  each target for 600 s (the long run), one at a time
#   bash scripts/fuzz.sh 60               each target for 60 s
#   bash scripts/fuzz.sh 60 ply_fuzz      one target
#   FUZZ_PARALLEL=2 bash scripts/fuzz.sh  two targets at a time
#   bash scripts/fuzz.sh --ctest 30       first the C++ tests under the sanitizers (what
#                                         scripts/test.sh runs), then 30 s per target
#
# Targets: scene_fuzz (tokenizer, parser, scene builder), ply_fuzz (PLY reader), table_fuzz
# (wavelength_table/include/wavelength_table.h). Each starts from the seeds in the repository
# (renderer/fuzz/corpus/<kind>, wavelength_table/fuzz/corpus/table) and the inputs that once crashed
# (.../regressions/<kind>); new interesting inputs collect in build-fuzz/corpus/<target>,
# crashes in build-fuzz/artifacts/. A crash, sanitizer report, hang (> 10 s per input), leak
# or more than 2 GB of memory fails the run; keep the input as a regression (see
# renderer/fuzz/README.md). Logs: build-fuzz/logs/<target>.log; the summary line of each
# target prints its executions and coverage.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BUILD=${FUZZ_BUILD:-build-fuzz}

log() { printf '\033[1m[fuzz]\033[0m %s\n' "$*" >&2; }

run_ctest=0
if [ "${1:-}" = "--ctest" ]; then run_ctest=1; shift; fi
SECONDS_PER_TARGET=${1:-600}
shift || true
TARGETS=("$@")
((${#TARGETS[@]})) || TARGETS=(scene_fuzz ply_fuzz table_fuzz)

command -v clang++ >/dev/null || { log "clang++ is not installed (scripts/setup.sh installs clang and libclang-rt-14-dev)"; exit 1; }

# --- Build (incremental) -----------------------------------------------------------------------
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  GEN=""; command -v ninja >/dev/null && GEN="-G Ninja"
  LAUNCHER=""; command -v ccache >/dev/null && LAUNCHER="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
  # The RGB-to-spectrum tables of the main build, when there is one, are copied, not recomputed.
  FROM=""; [ -f build/rgbspectrum_srgb.cpp ] && FROM="-DPBRT_RGB2SPEC_FROM=$ROOT/build"
  log "configuring $BUILD (clang, -DPBRT_FUZZ=ON: ASan + UBSan + libFuzzer)"
  cmake -S . -B "$BUILD" $GEN -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DPBRT_FUZZ=ON $LAUNCHER $FROM >/dev/null || exit 1
fi
build_targets=("${TARGETS[@]}")
((run_ctest)) && build_targets+=(pbrt_test wavelength_table_test)
log "building ${build_targets[*]} in $BUILD"
CCACHE_BASEDIR=${CCACHE_BASEDIR:-$ROOT} cmake --build "$BUILD" --parallel "$(nproc)" \
  --target "${build_targets[@]}" || exit 1

status=0
# UBSan reports fail (the code is built with -fno-sanitize-recover); print a stack for them.
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}

# --- The C++ tests under the sanitizers ------------------------------------------------------------
if ((run_ctest)); then
  log "C++ tests under ASan + UBSan"
  ( cd "$BUILD" && ctest --output-on-failure --parallel "$(nproc)" ) || status=1
fi

# --- Fuzzing -------------------------------------------------------------------------------------------
seeds() {
  case $1 in
    scene_fuzz) echo "renderer/fuzz/corpus/scene renderer/fuzz/regressions/scene" ;;
    ply_fuzz) echo "renderer/fuzz/corpus/ply renderer/fuzz/regressions/ply" ;;
    table_fuzz) echo "wavelength_table/fuzz/corpus/table wavelength_table/fuzz/regressions/table" ;;
  esac
}
dict() {
  case $1 in
    scene_fuzz) echo "-dict=renderer/fuzz/scene.dict" ;;
    ply_fuzz) echo "-dict=renderer/fuzz/ply.dict" ;;
    table_fuzz) echo "-dict=wavelength_table/fuzz/table.dict" ;;
  esac
}
fuzz_one() {
  local t=$1 dirs=()
  for d in $(seeds "$t"); do [ -d "$d" ] && dirs+=("$d"); done
  mkdir -p "$BUILD/corpus/$t" "$BUILD/artifacts" "$BUILD/logs"
  # The first directory receives new inputs: the repository's seeds stay as they are.
  "$BUILD/fuzz/$t" "$BUILD/corpus/$t" "${dirs[@]}" $(dict "$t") \
    -max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$BUILD/artifacts/$t-" >"$BUILD/logs/$t.log" 2>&1
  local rc=$?
  local execs cov
  execs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$BUILD/logs/$t.log" | grep -o '[0-9]*$')
  cov=$(grep -E '^#[0-9]+' "$BUILD/logs/$t.log" | tail -1 | grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+/[0-9]+[a-zA-Z]*')
  if ((rc == 0)); then
    log "$t: ok, ${SECONDS_PER_TARGET} s, ${execs:-?} executions, ${cov:-?}"
  else
    log "$t: FAILED (exit $rc); see $BUILD/logs/$t.log and $BUILD/artifacts/"
    grep -E 'ERROR|SUMMARY|runtime error|Test unit written' "$BUILD/logs/$t.log" | head -5 >&2
  fi
  return $rc
}

if ((SECONDS_PER_TARGET > 0)); then
  parallel=${FUZZ_PARALLEL:-1}
  pids=()
  for t in "${TARGETS[@]}"; do
    log "fuzzing $t for ${SECONDS_PER_TARGET} s"
    fuzz_one "$t" &
    pids+=($!)
    if ((${#pids[@]} >= parallel)); then
      wait "${pids[0]}" || status=1
      pids=("${pids[@]:1}")
    fi
  done
  for p in "${pids[@]}"; do wait "$p" || status=1; done
fi
exit $status
