#!/usr/bin/env bash
# multislit on a fresh Debian 12 machine:
#   bash run.sh demo   install what is missing, build (Release, build/), run the main job
#   bash run.sh test   install what is missing, build, run every test in build/ (Release) and in
#                      build-asan/ (AddressSanitizer + UndefinedBehaviorSanitizer)
#   bash run.sh tsan   install what is missing, build the tests of the threaded code (grabber,
#                      sources, the walk) in build-tsan/ with ThreadSanitizer and run them
#   bash run.sh fuzz [SECONDS]   build the libFuzzer targets of fuzz/ with clang (build-fuzz/) and
#                      run each from its seed corpus until 1 000 000 executions (FUZZ_RUNS), or
#                      for at most SECONDS (default 3600)
set -euo pipefail

# ==== THE MAIN JOB: the one command `bash run.sh demo` runs (replace it, keep it one line) ====
DEMO=(build/multislit walk --out out/walk)

PACKAGES=(cmake g++ make pkg-config libpcl-dev libopencv-dev liboctomap-dev libaravis-dev
  libeigen3-dev libflann-dev libgtest-dev libbenchmark-dev octomap-tools clang-format lld
  ninja-build
  # Debian's ROS 1, for the node apps/ros and its test: roscpp, TF, the messages, gencpp with
  # std_msgs' .msg files, roscore and roslaunch, rosbag record and info; genpy and rostopic for
  # the messages' Python modules and their test
  libroscpp-dev libtf2-ros-dev libpcl-conversions-dev libsensor-msgs-dev libvisualization-msgs-dev
  libnav-msgs-dev libdiagnostic-msgs-dev python3-gencpp ros-std-msgs python3-roslaunch
  python3-rosbag python3-genpy python3-std-msgs python3-rostopic)

cd "$(dirname "${BASH_SOURCE[0]}")"
JOBS=$(nproc)
# CTest runs one test more than there are cores: the camera tests spend much of their time waiting
# on timeouts (a camera that stops, a frame that never comes), and the extra test uses that time.
TEST_JOBS=$((JOBS + 1))

usage() {
  echo "usage: bash run.sh demo | test | tsan | fuzz [SECONDS]" >&2
  exit 2
}

# Section headers with the time each section took.
now() { date +%s%N; }
section_start=
section_name=
section() {
  section_end
  section_name=$1
  section_start=$(now)
  echo "== $section_name"
}
section_end() {
  if [[ -n $section_start ]]; then
    local ms=$((($(now) - section_start) / 1000000))
    printf '   %s: %d.%01d s\n' "$section_name" $((ms / 1000)) $((ms % 1000 / 100))
    SUMMARY+=("$(printf '%-26s %4d.%01d s' "$section_name" $((ms / 1000)) $((ms % 1000 / 100)))")
  fi
  section_start=
}
SUMMARY=()

as_root() {
  if ((EUID == 0)); then
    "$@"
  elif command -v sudo >/dev/null; then
    sudo "$@"
  else
    echo "run.sh: not root and no sudo; as root run: apt-get install ${missing[*]}" >&2
    exit 1
  fi
}

install_packages() {
  section "installing"
  if ! command -v dpkg-query >/dev/null; then
    echo "run.sh: dpkg-query not found; this script expects Debian 12" >&2
    exit 1
  fi
  missing=()
  local p status
  for p in "${PACKAGES[@]}"; do
    status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
    [[ $status == "install ok installed" ]] || missing+=("$p")
  done
  if ((${#missing[@]} == 0)); then
    echo "   all ${#PACKAGES[@]} packages present"
  else
    echo "   missing: ${missing[*]}"
    as_root env DEBIAN_FRONTEND=noninteractive apt-get update
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
      "${missing[@]}"
  fi
}

# configure_and_build <build dir> <cmake --build arguments...> -- <cmake configure options...>
configure_and_build() {
  local dir=$1 build_args=() configure_args=()
  shift
  while (($#)) && [[ $1 != -- ]]; do
    build_args+=("$1")
    shift
  done
  (($#)) && shift
  configure_args=("$@")
  # Ninja for a new build tree (4 s less than Make for Release, 8 s sanitized); an older tree keeps
  # its own generator.
  if [[ ! -f $dir/CMakeCache.txt ]] && command -v ninja >/dev/null; then
    configure_args=(-G Ninja "${configure_args[@]}")
  fi
  cmake -S . -B "$dir" "${configure_args[@]}"
  cmake --build "$dir" -j"$JOBS" "${build_args[@]}"
}

run_demo() {
  install_packages
  section "building"
  # The demo needs the command; with the filters everything `cmake --install build` installs is
  # built too. `bash run.sh test` builds everything.
  configure_and_build build --target multislit_cli multislit_filters -- -DCMAKE_BUILD_TYPE=Release
  section "demo"
  "${DEMO[@]}"
  section_end
  # Where the outputs are: the folder given to --out.
  local i
  for ((i = 0; i + 1 < ${#DEMO[@]}; i++)); do
    if [[ ${DEMO[i]} == --out ]]; then
      echo "== outputs: $(find "${DEMO[i + 1]}" -maxdepth 1 -type f | wc -l) files in" \
        "$(pwd)/${DEMO[i + 1]}/"
    fi
  done
}

# The sanitized builds: -O1 -g1 (line tables: reports keep file and line) compiles in 0.6x the
# time of -O2 -g; no benchmarks.
# The ROS node and its test (3 minutes more under the sanitizers on 2 cores) run in the Release
# build only; with -DMULTISLIT_ROS=ON they pass under ASan+UBSan too (ros_node: 57 s).
SANITIZED_BUILD=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DBUILD_TESTING=ON
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DMULTISLIT_BUILD_BENCHMARKS=OFF
  -DMULTISLIT_ROS=OFF)

print_times() {
  section_end
  echo "== times"
  printf '   %s\n' "${SUMMARY[@]}"
}

run_tests() {
  local failed=()
  install_packages
  section "building"
  configure_and_build build -- -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON
  section "testing (release)"
  ctest --test-dir build --output-on-failure -j"$TEST_JOBS" || failed+=("release")
  section "building (ASan+UBSan)"
  configure_and_build build-asan -- -DMULTISLIT_SANITIZE=ON "${SANITIZED_BUILD[@]}"
  section "testing (ASan+UBSan)"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j"$TEST_JOBS" || failed+=("ASan+UBSan")
  print_times
  if ((${#failed[@]})); then
    echo "== FAILED: tests of ${failed[*]}" >&2
    exit 1
  fi
  echo "== all tests passed"
}

# The tests labelled tsan (tests/CMakeLists.txt) and their programs.
TSAN_TARGETS=(grabber_test grabber_gige_test sources_test pipeline_test walker_test)

run_tsan() {
  install_packages
  section "building (TSan)"
  configure_and_build build-tsan --target "${TSAN_TARGETS[@]}" -- -DMULTISLIT_TSAN=ON \
    "${SANITIZED_BUILD[@]}"
  section "testing (TSan)"
  local status=0
  TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$(pwd)/tests/tsan.supp" \
    ctest --test-dir build-tsan --output-on-failure --no-tests=error -j"$JOBS" -L tsan || status=$?
  print_times
  if ((status)); then
    echo "== FAILED: tests under ThreadSanitizer" >&2
    exit 1
  fi
  echo "== all tests passed under ThreadSanitizer"
}

# Executions each fuzz target runs (issue 39 asks 1M of the file readers); SECONDS caps the time.
FUZZ_RUNS=${FUZZ_RUNS:-1000000}

# fuzz_one <target> <seconds>: libFuzzer on a fresh copy of fuzz/corpus/<target>/ in
# build-fuzz/runs/<target>/ until FUZZ_RUNS executions or <seconds>; prints its executions, the
# time they took and what it found (it stops at its first crash, timeout, leak or memory blow-up,
# and keeps the input in crashes/). Returns 1 when it found any.
fuzz_one() {
  local name=$1 seconds=$2 dir=build-fuzz/runs/$1 extra=() stats runs rate found start took
  rm -rf "$dir"
  mkdir -p "$dir/corpus" "$dir/crashes"
  cp fuzz/corpus/"$name"/* "$dir/corpus/"
  case $name in sensor | calibration | scene) extra=(-dict=fuzz/yaml.dict) ;; esac
  # Inputs at most the size of the largest seed that must stay whole (calibration/small.yaml,
  # 42 kB; sensor/crash-keys-on-one-line.yaml, 15 kB). The deep-nesting seeds (242 and 100 kB)
  # are cut there, still hundreds of times deeper than the limit of 64. Without a cap, inputs
  # grew to their size: 754 executions a second instead of 2251 (calibration, 300 s), 1M sensor
  # files in 379 s instead of 104 s.
  case $name in calibration) extra+=(-max_len=65536) ;; sensor) extra+=(-max_len=16384) ;; esac
  # -timeout: an input running 25 s is a hang; -close_fd_mask=1: the targets' stdout (--help).
  start=$(now)
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    build-fuzz/fuzz/fuzz_"$name" -runs="$FUZZ_RUNS" -max_total_time="$seconds" -timeout=25 \
    -rss_limit_mb=2048 -close_fd_mask=1 -print_final_stats=1 -artifact_prefix="$dir/crashes/" \
    "${extra[@]}" "$dir/corpus" </dev/null >"$dir/log" 2>&1 || true
  took=$((($(now) - start) / 1000000000))
  stats=$(grep -E '^stat::(number_of_executed_units|average_exec_per_sec):' "$dir/log" || true)
  runs=$(awk '/number_of_executed_units/ {print $2}' <<<"$stats")
  rate=$(awk '/average_exec_per_sec/ {print $2}' <<<"$stats")
  found=$(find "$dir/crashes" -type f | sort)
  printf '   fuzz_%-12s %10s executions in %5d s (%s/s), ' "$name" "${runs:-?}" "$took" "${rate:-?}"
  if [[ -z $found ]]; then
    echo "0 crashes"
    return 0
  fi
  echo "$(wc -l <<<"$found") crash(es): $(tr '\n' ' ' <<<"$found")(log: $dir/log;" \
    "replay: build-fuzz/fuzz/fuzz_$name FILE)"
  return 1
}

run_fuzz() {
  local seconds=$1 name crashed=()
  PACKAGES+=(clang libclang-rt-14-dev)
  install_packages
  section "building (clang, libFuzzer)"
  # Our code with -fsanitize=fuzzer-no-link,address,undefined, the targets with -fsanitize=fuzzer
  # (fuzz/CMakeLists.txt); -O2 -g1: fast, with file and line in reports.
  CC=clang CXX=clang++ configure_and_build build-fuzz --target fuzz_targets -- -DMULTISLIT_FUZZ=ON \
    -DBUILD_TESTING=OFF -DMULTISLIT_BUILD_BENCHMARKS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1"
  section "fuzzing ($FUZZ_RUNS executions or $seconds s per target)"
  while read -r name; do
    fuzz_one "$name" "$seconds" || crashed+=("fuzz_$name")
  done <build-fuzz/fuzz/targets.txt
  print_times
  if ((${#crashed[@]})); then
    echo "== FOUND crashes: ${crashed[*]}" >&2
    exit 1
  fi
  echo "== no crash"
}

(($# == 1)) || [[ $# == 2 && $1 == fuzz && $2 =~ ^[1-9][0-9]*$ ]] || usage
case $1 in
  demo) run_demo ;;
  test) run_tests ;;
  tsan) run_tsan ;;
  fuzz) run_fuzz "${2:-3600}" ;;
  *) usage ;;
esac
