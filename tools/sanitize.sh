#!/usr/bin/env bash
# The test suite under sanitizers, in build folders of their own:
#
#   tools/sanitize.sh address [ctest args]   ASan + UBSan (clang; with the fuzz targets of
#                                            tools/fuzz.sh) in build-asan/
#   tools/sanitize.sh thread  [ctest args]   TSan in build-tsan/, with oneTBB built with TSan
#                                            from Debian's source of the installed version
#                                            (build-tsan/onetbb/; Debian's libtbb is not
#                                            instrumented, so every parallel_for would look
#                                            like a race); tools/tsan.supp for the rest
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
# oneTBB 2021 from Debian's source package of the installed libtbb12, built with TSan, once.
# The source comes through apt lists of this folder's own (deb-src beside the machine's deb
# entries); the machine's apt configuration is left as it is.
tsan_tbb() {
  local dir=$PWD/build-tsan/onetbb apt
  [ -f "$dir/lib/libtbb.so.12" ] && return
  rm -rf "$dir" && mkdir -p "$dir/apt/parts" "$dir/apt/lists/partial" "$dir/src"
  if [ -f /etc/apt/sources.list.d/debian.sources ]; then
    sed 's/^Types: deb$/Types: deb-src/' /etc/apt/sources.list.d/debian.sources > "$dir/apt/parts/src.sources"
  else
    sed -n 's/^deb /deb-src /p' /etc/apt/sources.list > "$dir/apt/parts/src.list"
  fi
  apt=(-o Dir::Etc::SourceList=/dev/null -o Dir::Etc::SourceParts="$dir/apt/parts" -o Dir::State::Lists="$dir/apt/lists")
  apt-get "${apt[@]}" update -qq
  (cd "$dir/src" && apt-get "${apt[@]}" source --download-only "onetbb=$(dpkg-query -W -f='${Version}' libtbb12)")
  tar xJf "$dir"/src/onetbb_*.orig.tar.xz -C "$dir/src"
  cmake -S "$(ls -d "$dir"/src/oneTBB-*/)" -B "$dir/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DTBB_SANITIZE=thread -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF -DTBB_STRICT=OFF
  cmake --build "$dir/build" --target tbb
  mkdir -p "$dir/lib" && cp -a "$dir"/build/*/libtbb.so* "$dir/lib/"
}
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
    tsan_tbb
    export LD_LIBRARY_PATH=$PWD/build-tsan/onetbb/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tools/tsan.supp} ;;
  *)
    sed -n '2,9p' "$0"; exit 2 ;;
esac
# SANITIZE_TARGETS="test_scene test_bake" builds only those (CI: the tests it runs).
cmake --build "$dir" ${SANITIZE_TARGETS:+--target $SANITIZE_TARGETS}
cd "$dir"
ctest --output-on-failure -j "$(nproc)" "$@"
