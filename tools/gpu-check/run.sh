#!/usr/bin/env bash
# Runs on the lent GPU machine (see prepare.sh): the GPU tests, the per-kernel bench, and the
# Cycles Cornell boxes baked and path-traced on the CPU and on the GPU. Writes under $OUT:
# machine.txt (what ran, exit codes, seconds), test_cuda.txt, microbench.txt, runs.txt and
# files.tar.xz (bake.json, lightmaps and images of each run, to compare here).
set -uo pipefail
root=$PWD t0=$SECONDS
mkdir -p /opt/vl && tar xJf .gpu/libs.tar.xz -C /opt/vl && tar xJf .gpu/bins.tar.xz -C /opt/vl
# The test binaries find scenes/ through the source folder compiled into them.
[ -e /work/main ] || { mkdir -p /work && ln -s "$root" /work/main; }
L="env LD_LIBRARY_PATH=/opt/vl/lib" B=/opt/vl/bin  # our binaries only: the stubs would break system tools
log() { echo "$* at $((SECONDS - t0)) s" >> "$OUT/machine.txt"; }
{ nvidia-smi -L; nproc; grep PRETTY /etc/os-release; } > "$OUT/machine.txt" 2>&1
cd /work/main
timeout 240 $L $B/test_cuda -r console -d yes > "$OUT/test_cuda.txt" 2>&1; log "test_cuda rc=$?"
timeout 200 $L $B/microbench_cuda > "$OUT/microbench.txt" 2>&1; log "microbench rc=$?"
timeout 150 $L $B/microbench_cuda .gpu/scenes/cornell_quad.gltf --spp 256 >> "$OUT/microbench.txt" 2>&1; log "microbench quad rc=$?"
mkdir -p /tmp/o
for s in cornell_quad cornell_point; do
  for d in cpu cuda; do
    timeout 60 $L $B/voxlight bake .gpu/scenes/$s.gltf -o /tmp/o/${s}_$d --device $d --gltf false --grids false >> "$OUT/runs.txt" 2>&1
    log "bake $s $d rc=$?"
    timeout 90 $L $B/voxlight reference .gpu/scenes/$s.gltf --spp 1024 -o /tmp/o/ref_${s}_$d --device $d >> "$OUT/runs.txt" 2>&1
    log "reference $s $d rc=$?"
  done
done
(cd /tmp/o && find . -name '*.json' -o -name lightmap.exr -o -name lightmap_indirect.exr -o -name image.exr |
  tar cJf "$OUT/files.tar.xz" -T -)
log done
