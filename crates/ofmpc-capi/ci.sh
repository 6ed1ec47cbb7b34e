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
python3 - "$work/run/metrics.json" "$work/c.txt" "$work/cpp.txt" <<'PY'
import json, sys
run = json.load(open(sys.argv[1]))["runs"][0]
want = {
    "cartesian_error_rms_mm": run["cartesian_error_rms_mm"],
    "cartesian_error_max_mm": run["cartesian_error_max_mm"],
    "steady_cartesian_error_mm": run["steady_cartesian_error_mm"],
    "steady_joint_error_max_rad": max(run["steady_joint_error_max_rad"]),
}
def read(path):
    out = {}
    for line in open(path):
        key, _, value = line.rstrip().rpartition(" ")
        out[key] = value
    return out
bad = 0
for path, prefixes in ((sys.argv[2], [""]), (sys.argv[3], ["direct ", "ros2 "])):
    got = read(path)
    for p in prefixes:
        for k, w in want.items():
            g = float(got[p + k])
            rel = abs(g - w) / max(abs(w), 1e-300)
            ok = rel <= 1e-12
            bad += not ok
            print(f"{'ok ' if ok else 'BAD'} {path.split('/')[-1]} {p}{k}: {g!r} vs ofmpc run {w!r} (rel {rel:.1e})")
        print(f"    step time p50 {got[p + 'step_us_p50']} us, p99 {got[p + 'step_us_p99']} us, max {got[p + 'step_us_max']} us")
sys.exit(1 if bad else 0)
PY
echo "C API: examples match ofmpc run, valgrind clean"
