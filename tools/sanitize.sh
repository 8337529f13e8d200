#!/usr/bin/env bash
# The test suite under sanitizers, in build folders of their own:
#
#   tools/sanitize.sh address [ctest args]   ASan + UBSan (clang; with the fuzz targets of
#                                            tools/fuzz.sh) in build-asan/
#   tools/sanitize.sh thread  [ctest args]   TSan in build-tsan/
#
# With no ctest arguments every test runs; e.g. `-R '^(scene|voxel):'` picks some (and
# SANITIZE_TARGETS="test_scene test_voxel" builds only their programs). A finding
# (an invalid access, a leak, undefined behaviour, a data race) fails the test that met it.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-address}
shift || true
tools/install-deps.sh sanitizers
export ASAN_SYMBOLIZER_PATH=${ASAN_SYMBOLIZER_PATH:-/usr/lib/llvm-14/bin/llvm-symbolizer}
export UBSAN_SYMBOLIZER_PATH=${UBSAN_SYMBOLIZER_PATH:-$ASAN_SYMBOLIZER_PATH}
common=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DVOXLIGHT_BENCHMARKS=OFF -DVOXLIGHT_CUDA=OFF)
case "$mode" in
  address)
    dir=build-asan
    cmake -S . -B "$dir" "${common[@]}" -DVOXLIGHT_SANITIZE=address,undefined -DVOXLIGHT_FUZZ=ON
    export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
    export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp}
    export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1} ;;
  thread)
    dir=build-tsan
    cmake -S . -B "$dir" "${common[@]}" -DVOXLIGHT_SANITIZE=thread
    export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1} ;;
  *)
    sed -n '2,9p' "$0"; exit 2 ;;
esac
# SANITIZE_TARGETS="test_scene test_bake" builds only those (CI: the tests it runs).
cmake --build "$dir" ${SANITIZE_TARGETS:+--target $SANITIZE_TARGETS}
cd "$dir"
ctest --output-on-failure -j "$(nproc)" "$@"
