// libFuzzer: the glTF loader on one .glb file (binary chunks, embedded images).
#define FUZZ_EXTENSION ".glb"
#include "tools/fuzz/fuzz_gltf.cpp"
