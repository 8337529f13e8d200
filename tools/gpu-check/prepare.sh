#!/usr/bin/env bash
# Prepares the GPU check (issue 7) for a lent GPU machine (the `device` tool): builds with
# CUDA, bundles the binaries with their libraries (bundle.py) and the Cycles Cornell boxes
# into .gpu/ (git-ignored locally through .git/info/exclude), ready to carry:
#
#   tools/gpu-check/prepare.sh                 # here, after tools/build.sh
#   device run: bash tools/gpu-check/run.sh    # there, carry [".gpu"]; results under $OUT
set -euo pipefail
cd "$(dirname "$0")/../.."
[ -x /usr/local/cuda/bin/nvcc ] || { echo "no nvcc: the CUDA launchers would not be built" >&2; exit 1; }
tools/build.sh >/dev/null
grep -qx '/.gpu/' .git/info/exclude 2>/dev/null || echo '/.gpu/' >> .git/info/exclude
rm -rf .gpu && mkdir -p .gpu/scenes
tools/gpu-check/bundle.py .gpu build/voxlight build/tests/test_cuda build/microbench/microbench_cuda
cp ../shared/reference/cornell_{quad,point}.gltf ../shared/reference/cbox_{quad,point}_spec.bin .gpu/scenes/
du -sh .gpu
