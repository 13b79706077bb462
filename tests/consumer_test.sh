#!/usr/bin/env bash
# Installs zwidth to a temporary prefix and builds and runs tests/consumer
# against it with find_package(zwidth). Usage: consumer_test.sh BUILD_DIR SRC
set -euo pipefail
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
cmake --install "$1" --prefix "$T/prefix" >/dev/null
cmake -S "$2/tests/consumer" -B "$T/build" -DCMAKE_PREFIX_PATH="$T/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$T/build" -j2 >/dev/null
"$T/build/consumer"
