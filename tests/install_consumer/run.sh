#!/usr/bin/env bash
# Proves the installed package works: installs component `client` of a primlabel build into a
# temporary prefix, configures and builds this directory's project against it with
# find_package(primlabel), and runs it (it labels against 127.0.0.1:1 and expects a clean error).
#   run.sh BUILD_DIR [CMAKE] [CXX_COMPILER]
# Everything happens in a temporary directory under BUILD_DIR, removed on exit. Uses ccache when
# it is installed. CTest: install.Consumer (label integration).
set -euo pipefail

[[ $# -ge 1 && -d $1 ]] || { echo "usage: $0 BUILD_DIR [CMAKE] [CXX_COMPILER]" >&2; exit 2; }
build=$(cd "$1" && pwd)
cmake=${2:-cmake}
cxx=${3:-}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
source_dir=$(cd "$here/../.." && pwd)

tmp=$(mktemp -d "$build/install_consumer.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
log() { printf '== %s\n' "$*"; }

log "install component client into $prefix"
"$cmake" --install "$build" --prefix "$prefix" --component client

# The installed package must not point back into the build or source tree.
config=$(find "$prefix" -name primlabelConfig.cmake)
[[ -n $config ]] || { log "FAIL: no primlabelConfig.cmake under $prefix"; exit 1; }
if leaks=$(find "$prefix" -name '*.cmake' -exec grep -lF -e "$build" -e "$source_dir" {} +); then
  log "FAIL: installed CMake files name the build or source tree:"
  printf '%s\n' "$leaks"
  exit 1
fi

launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Paths under the temporary directory become relative, so repeated runs hit the cache.
  export CCACHE_BASEDIR=$tmp CCACHE_NOHASHDIR=1
fi
log "configure the consumer"
"$cmake" -S "$here" -B "$tmp/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF ${cxx:+-DCMAKE_CXX_COMPILER="$cxx"} "${launcher[@]}"
found=$(sed -n 's/^primlabel_DIR:PATH=//p' "$tmp/build/CMakeCache.txt")
[[ $found == "$prefix"/* ]] || { log "FAIL: found primlabel in '$found', not under $prefix"; exit 1; }

log "build the consumer"
"$cmake" --build "$tmp/build"

log "run the consumer"
"$tmp/build/robot_app"

# What the robot's build must find: gRPC, protobuf and geometry's own dependencies, nothing of
# libsvm, libpng, zlib or prometheus-cpp (the server's and the rest of core's).
targets=$(find "$prefix" -name 'primlabelTargets*.cmake' -exec cat {} +)
for forbidden in svm png PNG ZLIB prometheus server; do
  if grep -q -- "$forbidden" <<<"$targets"; then
    log "FAIL: the installed targets name '$forbidden'"
    exit 1
  fi
done
for proto in labeling.proto model.proto; do
  [[ -f $prefix/include/primlabel/v1/$proto ]] || { log "FAIL: $proto not installed"; exit 1; }
done

log "build the consumer again with pkg-config (primlabel-client.pc), without CMake"
pc=$(find "$prefix" -name primlabel-client.pc)
[[ -n $pc ]] || { log "FAIL: no primlabel-client.pc under $prefix"; exit 1; }
export PKG_CONFIG_PATH=$(dirname "$pc")
# shellcheck disable=SC2046
${cxx:-c++} -std=c++20 -O1 -o "$tmp/robot_app_pc" "$here/main.cpp" \
  $(pkg-config --cflags --libs primlabel-client)
"$tmp/robot_app_pc"
log "OK"
