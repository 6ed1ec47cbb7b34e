#!/usr/bin/env bash
# CI of the C API (called by .ci/run): install it under target/capi-prefix, build the C and C++
# examples with the system's gcc/g++ through pkg-config (shared library), run them under
# valgrind (memcheck: any error fails), and compare their metrics with the real `ofmpc run`'s
# metrics.json for the same scenario (1e-12 relative). The ASAN build against the static
# library is the Rust test tests/examples.rs (part of `cargo test --release`).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
cd "$root"
for tool in gcc g++ pkg-config valgrind python3; do
  command -v "$tool" >/dev/null 2>&1 || { echo "error: $tool is needed by the C API's CI (apt-get install $tool)" >&2; exit 1; }
done
prefix="$root/target/capi-prefix"
work="$root/target/capi-ci"
rm -rf "$work" && mkdir -p "$work"
"$here/install.sh" "$prefix" >/dev/null
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
flags=(-O2 -g -Wall -Wextra -Werror -Wl,-rpath,"$prefix/lib")
gcc -std=c11 "${flags[@]}" "$here/examples/paper_loop.c" $(pkg-config --cflags --libs ofmpc) -o "$work/paper_loop"
g++ -std=c++17 "${flags[@]}" "$here/examples/paper_loop.cpp" $(pkg-config --cflags --libs ofmpc) -o "$work/paper_loop_cpp"

scenario="$here/examples/paper.toml"
gcode="$root/examples/paper-table1.gcode"
vg=(valgrind --quiet --error-exitcode=42 --leak-check=full --errors-for-leak-kinds=definite)
"${vg[@]}" "$work/paper_loop" "$scenario" "$gcode" second 0.25 > "$work/c.txt"
"${vg[@]}" "$work/paper_loop_cpp" "$scenario" "$gcode" second 0.25 > "$work/cpp.txt"

cargo build --release -p ofmpc-cli >/dev/null 2>&1
"$root/target/release/ofmpc" run "$scenario" --out "$work/run" >/dev/null
compare() { python3 "$here/compare_metrics.py" "$@"; }
compare "$work/run/metrics.json" "$work/c.txt" "" "$work/cpp.txt" "direct " "$work/cpp.txt" "ros2 "

# The paper's path at 1 kHz (N = 100, structured solver), natively (valgrind would take long).
fast="$root/examples/paper-1khz.toml"
"$work/paper_loop" "$fast" "$gcode" second 0.25 > "$work/c-1khz.txt"
"$root/target/release/ofmpc" run "$fast" --out "$work/run-1khz" >/dev/null
compare "$work/run-1khz/metrics.json" "$work/c-1khz.txt" ""
echo "C API: examples match ofmpc run, valgrind clean"
