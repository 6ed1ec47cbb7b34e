"""Compares the metrics printed by the C/C++ examples with `ofmpc run`'s metrics.json.

usage: compare_metrics.py METRICS.json OUTPUT.txt PREFIX [OUTPUT.txt PREFIX ...]
Exit 1 when a metric differs by more than 1e-12 relative."""
import json
import sys

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
pairs = sys.argv[2:]
for path, prefix in zip(pairs[::2], pairs[1::2]):
    got = read(path)
    name = path.split("/")[-1]
    for k, w in want.items():
        g = float(got[prefix + k])
        rel = abs(g - w) / max(abs(w), 1e-300)
        ok = rel <= 1e-12
        bad += not ok
        print(f"{'ok ' if ok else 'BAD'} {name} {prefix}{k}: {g!r} vs ofmpc run {w!r} (rel {rel:.1e})")
    p = prefix
    print(f"    step time p50 {got[p + 'step_us_p50']} us, p99 {got[p + 'step_us_p99']} us, "
          f"max {got[p + 'step_us_max']} us")
sys.exit(1 if bad else 0)
