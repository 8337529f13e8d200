#!/usr/bin/env bash
# libFuzzer on the readers of files from anywhere (tools/fuzz/), built with clang, ASan and
# UBSan into build-asan/.
#
#   tools/fuzz.sh build                   configure and build the targets
#   tools/fuzz.sh run TARGET SECONDS [FLAGS]
#                                         fuzz one target, growing build-asan/corpus/TARGET
#                                         from tools/fuzz/corpus/TARGET; findings land in
#                                         build-asan/findings/TARGET/; FLAGS go to libFuzzer
#   tools/fuzz.sh minimise TARGET         merge build-asan/corpus/TARGET into the committed
#                                         corpus, smallest inputs that keep its coverage, each
#                                         cut to 6000 bytes (the corpora stay under 5 MB)
#   tools/fuzz.sh replay                  every committed input of every target once (CI)
#
# Targets: fuzz_gltf fuzz_glb fuzz_image fuzz_job_file fuzz_vdb. Limits: 10 s an input
# (a hang), 2 GB resident, and no single allocation over 1 GB (an input claiming a huge size
# must be refused before it is allocated). Leaks in libraries that cannot be fixed here are
# listed, with reasons, in tools/lsan.supp. A length a library allocates before reading it
# (OpenVDB's strings and compressed blocks) is capped by voxlight (core/allocation_limit.h).
set -euo pipefail
cd "$(dirname "$0")/.."
targets=(fuzz_gltf fuzz_glb fuzz_image fuzz_job_file fuzz_vdb)
limits=(-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024)
# fast_unwind_on_malloc=0: a leak's allocation stack goes on through libopenvdb, which keeps
# no frame pointers, to a frame tools/lsan.supp can name.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0:fast_unwind_on_malloc=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export ASAN_SYMBOLIZER_PATH=${ASAN_SYMBOLIZER_PATH:-/usr/lib/llvm-14/bin/llvm-symbolizer}
export UBSAN_SYMBOLIZER_PATH=${UBSAN_SYMBOLIZER_PATH:-$ASAN_SYMBOLIZER_PATH}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp}

case "${1:-}" in
  build)
    tools/install-deps.sh sanitizers
    cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
      -DVOXLIGHT_FUZZ=ON -DVOXLIGHT_SANITIZE=address,undefined \
      -DVOXLIGHT_BENCHMARKS=OFF -DVOXLIGHT_CUDA=OFF
    cmake --build build-asan --target "${targets[@]}" ;;
  run)
    target=$2 seconds=$3
    shift 3
    mkdir -p "build-asan/corpus/$target" "build-asan/findings/$target"
    "build-asan/fuzz/$target" "${limits[@]}" -max_total_time="$seconds" -print_final_stats=1 \
      -artifact_prefix="build-asan/findings/$target/" "$@" "build-asan/corpus/$target" "tools/fuzz/corpus/$target" ;;
  minimise)
    target=$2
    mkdir -p "build-asan/merged/$target" "build-asan/findings/$target"
    rm -rf "build-asan/merged/$target"/*
    "build-asan/fuzz/$target" "${limits[@]}" -max_len=6000 -merge=1 -artifact_prefix="build-asan/findings/$target/" \
      "build-asan/merged/$target" "tools/fuzz/corpus/$target" "build-asan/corpus/$target"
    rm -rf "tools/fuzz/corpus/$target"
    cp -r "build-asan/merged/$target" "tools/fuzz/corpus/$target" ;;
  replay)
    for target in "${targets[@]}"; do
      echo "replaying tools/fuzz/corpus/$target ($(ls "tools/fuzz/corpus/$target" | wc -l) inputs)"
      # An input that fails is written under build-asan/findings/, not into the working tree.
      mkdir -p "build-asan/findings/$target"
      "build-asan/fuzz/$target" "${limits[@]}" -runs=0 -artifact_prefix="build-asan/findings/$target/" \
        "tools/fuzz/corpus/$target"
    done ;;
  *)
    sed -n '2,16p' "$0"; exit 2 ;;
esac
