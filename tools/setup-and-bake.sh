#!/usr/bin/env bash
# Quick start 1: install, build, bake the default Cornell box into output/.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
tools/build.sh
build/voxlight bake "$@"
