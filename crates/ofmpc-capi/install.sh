#!/usr/bin/env bash
# Builds the C API in release and installs it under PREFIX (default /usr/local):
#   PREFIX/include/ofmpc.h, ofmpc.hpp
#   PREFIX/lib/libofmpc_capi.so, libofmpc_capi.a
#   PREFIX/lib/pkgconfig/ofmpc.pc                (pkg-config --cflags --libs ofmpc)
#   PREFIX/lib/cmake/ofmpc/ofmpcConfig.cmake     (find_package(ofmpc), targets ofmpc::ofmpc,
#   PREFIX/lib/cmake/ofmpc/ofmpcConfigVersion.cmake               ofmpc::ofmpc_static)
# Needs only cargo. Usage: crates/ofmpc-capi/install.sh [PREFIX]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
prefix="$(mkdir -p "${1:-/usr/local}" && cd "${1:-/usr/local}" && pwd)"
version="$(sed -n 's/^#define OFMPC_VERSION "\(.*\)"$/\1/p' "$here/include/ofmpc.h")"
major="${version%%.*}"; rest="${version#*.}"; minor="${rest%%.*}"

(cd "$root" && cargo build --release -p ofmpc-capi)
target="${CARGO_TARGET_DIR:-$root/target}/release"

install -d "$prefix/include" "$prefix/lib/pkgconfig" "$prefix/lib/cmake/ofmpc"
install -m 644 "$here/include/ofmpc.h" "$here/include/ofmpc.hpp" "$prefix/include/"
install -m 755 "$target/libofmpc_capi.so" "$prefix/lib/"
install -m 644 "$target/libofmpc_capi.a" "$prefix/lib/"
subst() { sed -e "s|@PREFIX@|$prefix|g" -e "s|@VERSION@|$version|g" -e "s|@MAJOR@|$major|g" -e "s|@MINOR@|$minor|g" "$1"; }
subst "$here/cmake/ofmpc.pc.in" > "$prefix/lib/pkgconfig/ofmpc.pc"
subst "$here/cmake/ofmpcConfig.cmake.in" > "$prefix/lib/cmake/ofmpc/ofmpcConfig.cmake"
subst "$here/cmake/ofmpcConfigVersion.cmake.in" > "$prefix/lib/cmake/ofmpc/ofmpcConfigVersion.cmake"
echo "installed ofmpc $version under $prefix"
