#!/usr/bin/env bash
# Installs the Debian 12 packages voxlight builds with, when any is missing.
set -euo pipefail
packages=(build-essential cmake ninja-build
  libopenvdb-dev libnanovdb-dev libblosc-dev libboost-iostreams-dev zlib1g-dev libopenimageio-dev openimageio-tools libtinygltf-dev
  libglm-dev libtbb-dev catch2 libcli11-dev nlohmann-json3-dev
  python3-openvdb libbenchmark-dev libembree-dev
  gnuplot-nox  # voxlight bench draws its plot with gnuplot; the optional Cycles peer needs blender
  nodejs  # runs the Khronos glTF validator (tools/gltf-validator) on every scene.glb in the tests
  chromium  # voxlight view --screenshot, and the test of the viewer page in a real browser
  slurm-wlm munge iproute2 procps)  # the one-node Slurm cluster the cluster bake's tests start (tools/cluster/test-cluster.sh)
# `tools/install-deps.sh sanitizers` (tools/sanitize.sh and tools/fuzz.sh call it; CI runs them):
# clang with its sanitizer runtimes (libclang-rt-14-dev: clang alone does not pull them),
# libFuzzer, and llvm-14's llvm-symbolizer (reports name functions, and tools/lsan.supp
# matches by name: without it the suppressions match nothing).
if [ "${1:-}" = sanitizers ]; then packages+=(clang libclang-rt-14-dev libfuzzer-14-dev llvm-14); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
