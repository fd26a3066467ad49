#!/bin/sh
# Builds the libFuzzer targets with clang (tests/fuzz as a CMake project of its own) and runs each
# for SECONDS (default 60), all three at once, from the seed corpora in tests/fuzz/corpus.
#   tests/fuzz/run.sh BUILD_DIR [SECONDS]
# Exit: 0 no finding, 1 a target crashed (its reproducer is in BUILD_DIR/artifacts), 77 skipped
# (no clang++ or no libFuzzer runtime; CTest's SKIP_RETURN_CODE).
set -u
build_dir=${1:?usage: run.sh BUILD_DIR [SECONDS]}
seconds=${2:-60}
here=$(cd "$(dirname "$0")" && pwd)

cxx=""
for candidate in clang++-14 clang++; do
  if command -v "$candidate" >/dev/null 2>&1; then cxx=$(command -v "$candidate"); break; fi
done
if [ -z "$cxx" ]; then
  echo "fuzz: skipped: no clang++ installed"
  exit 77
fi
probe=$(mktemp -d)
printf 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }\n' \
  >"$probe/probe.cpp"
if ! "$cxx" -fsanitize=fuzzer "$probe/probe.cpp" -o "$probe/probe" >/dev/null 2>&1; then
  rm -rf "$probe"
  echo "fuzz: skipped: $cxx cannot link -fsanitize=fuzzer (install libclang-rt-14-dev)"
  exit 77
fi
rm -rf "$probe"

launcher=""
command -v ccache >/dev/null 2>&1 && launcher="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
cmake -S "$here" -B "$build_dir" -DCMAKE_CXX_COMPILER="$cxx" $launcher >"$build_dir.configure.log" 2>&1 ||
  { cat "$build_dir.configure.log"; echo "fuzz: configure failed"; exit 1; }
cmake --build "$build_dir" -j2 || { echo "fuzz: build failed"; exit 1; }

# New inputs go to a working corpus in the build directory, never into the checked-in seeds.
mkdir -p "$build_dir/artifacts"
status=0
pids=""
for target in pcd_reader ply_reader request_decoding; do
  mkdir -p "$build_dir/corpus/$target"
  # -rss_limit_mb / -malloc_limit_mb: an input that makes a reader allocate what its header
  # claims, instead of what the file holds, is a finding.
  "$build_dir/fuzz_$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -malloc_limit_mb=1024 -print_final_stats=1 \
    -artifact_prefix="$build_dir/artifacts/$target-" \
    "$build_dir/corpus/$target" "$here/corpus/$target" >"$build_dir/$target.log" 2>&1 &
  pids="$pids $target:$!"
done
for entry in $pids; do
  target=${entry%%:*}
  if wait "${entry#*:}"; then
    echo "fuzz: $target: no finding in ${seconds} s ($(grep -m1 'stat::number_of_executed_units' "$build_dir/$target.log" | awk '{print $2}') runs)"
  else
    status=1
    echo "fuzz: $target: FINDING (log $build_dir/$target.log, reproducer in $build_dir/artifacts):"
    grep -E 'ERROR|SUMMARY|Test unit written' "$build_dir/$target.log" | head -5
  fi
done
exit $status
