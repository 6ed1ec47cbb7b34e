"""A parameter sweep of ofmpc scenarios on Dask: payloads × controllers × tunings.

Every grid point is one scenario (a dict with the keys of the TOML scenario file)
run by `ofmpc.run` on a Dask worker (in Rust, the GIL released); the results are
gathered into a table (CSV) and a figure (PNG). Here on a `LocalCluster`; the same
code runs on any Dask cluster: give `--scheduler tcp://host:8786`, or build the
cluster with dask-jobqueue on Slurm:

    from dask_jobqueue import SLURMCluster
    cluster = SLURMCluster(cores=1, memory="2GB", processes=1); cluster.scale(jobs=64)
    rows = run_sweep(Client(cluster), grid(...))

    python examples/python/sweep_dask.py --payloads 0,0.25,0.5,1 --workers 2 --out sweep-out

Every point can be repeated by the CLI: `scenario_toml(point)` is its scenario file.
Needs: `pip install ./crates/ofmpc-py "dask[distributed]" matplotlib`.
"""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import pathlib
import time
from typing import Any, Dict, List, Mapping, Optional, Sequence

import ofmpc

# Named tunings: overrides of the [mpc] section (the rest is the paper's tuning).
TUNINGS: Dict[str, Dict[str, Any]] = {
    "paper": {},
    "stiff": {"q_dy": 0.25},
    "long": {"horizon": 20},
}


# The scenario's shorthands for several controllers: one grid point per controller, so they
# are expanded here (issue #36: controllers=["paper"] made a point of three runs).
GROUPS = {
    "paper": ["usual", "first", "second"],
    "baselines": ["pid", "ctc", "ctc-adaptive", "dob-mpc"],
}
GROUPS["all"] = GROUPS["paper"] + ["first-adaptive", "second-adaptive"] + GROUPS["baselines"]


def expand(controllers: Sequence[str]) -> List[str]:
    """The controller names with the shorthands "paper", "baselines", "all" expanded."""
    return [k for c in controllers for k in GROUPS.get(c, [c])]


def grid(
    payloads: Sequence[float],
    controllers: Sequence[str],
    tunings: Mapping[str, Mapping[str, Any]],
    base: Optional[Mapping[str, Any]] = None,
) -> List[Dict[str, Any]]:
    """One scenario dict per payload × controller × tuning, built on `base`."""
    points = []
    for (name, tuning), kind, mass in itertools.product(tunings.items(), expand(controllers), payloads):
        s = json.loads(json.dumps(base or {}))  # deep copy
        s["title"] = f"{kind}, {mass} kg, tuning {name}"
        s["controllers"] = [kind]
        s.setdefault("payload", {})["masses_kg"] = [float(mass)]
        s["mpc"] = {**s.get("mpc", {}), **tuning}
        points.append({"tuning": name, "scenario": s})
    return points


def run_point(point: Mapping[str, Any]) -> Dict[str, Any]:
    """Runs one grid point (on a worker): the metrics of its single run, flattened."""
    t0 = time.perf_counter()
    metrics = ofmpc.run(point["scenario"])
    (run,) = metrics["runs"]
    return {"tuning": point["tuning"], **run, "task_s": time.perf_counter() - t0}


def run_sweep(client, points: Sequence[Mapping[str, Any]]) -> List[Dict[str, Any]]:
    """Maps `run_point` over the grid on the client's cluster, in grid order."""
    futures = client.map(run_point, points, pure=False)
    return client.gather(futures)


COLUMNS = [
    "tuning",
    "controller",
    "payload_kg",
    "cartesian_error_rms_mm",
    "cartesian_error_max_mm",
    "steady_cartesian_error_mm",
    "diverged",
    "task_s",
]


def write_table(rows: Sequence[Mapping[str, Any]], path: pathlib.Path) -> str:
    """Writes the CSV (every metric, per-joint lists as JSON) and returns a text table."""
    keys = list(rows[0].keys()) if rows else COLUMNS
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(keys)
        for r in rows:
            w.writerow([json.dumps(r[k]) if isinstance(r[k], (list, dict)) else r[k] for k in keys])
    lines = ["  ".join(f"{c:>24}" for c in COLUMNS)]
    for r in rows:
        lines.append("  ".join(f"{r[c]:>24.6g}" if isinstance(r[c], float) else f"{str(r[c]):>24}" for c in COLUMNS))
    return "\n".join(lines)


def write_figure(rows: Sequence[Mapping[str, Any]], path: pathlib.Path) -> None:
    """RMS and steady Cartesian error against payload, one line per controller × tuning."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    series: Dict[tuple, List[Mapping[str, Any]]] = {}
    for r in rows:
        series.setdefault((r["controller"], r["tuning"]), []).append(r)
    for (kind, tuning), rs in sorted(series.items()):
        rs = sorted(rs, key=lambda r: r["payload_kg"])
        x = [r["payload_kg"] for r in rs]
        for ax, key in zip(axes, ["cartesian_error_rms_mm", "steady_cartesian_error_mm"]):
            y = [max(r[key] if r[key] is not None else float("nan"), 1e-14) for r in rs]
            ax.semilogy(x, y, marker="o", label=f"{kind} / {tuning}")
            for r, yy in zip(rs, y):
                if r["diverged"]:
                    ax.plot([r["payload_kg"]], [yy], "rx", markersize=10)
    axes[0].set_title("RMS Cartesian error (mm)")
    axes[1].set_title("steady Cartesian error (mm); x: diverged")
    for ax in axes:
        ax.set_xlabel("payload unknown to the model (kg)")
        ax.grid(True, which="both", alpha=0.3)
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a JSON string is a valid TOML basic string
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as a TOML value")


def scenario_toml(scenario: Mapping[str, Any]) -> str:
    """The scenario file of a scenario dict (top-level keys, then one [section] per table)."""
    top = [f"{k} = {_toml_value(v)}" for k, v in scenario.items() if not isinstance(v, Mapping)]
    sections = []
    for k, v in scenario.items():
        if isinstance(v, Mapping):
            sections.append(f"[{k}]\n" + "\n".join(f"{kk} = {_toml_value(vv)}" for kk, vv in v.items()))
    return "\n".join(top) + "\n\n" + "\n\n".join(sections) + "\n"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--payloads", default="0,0.25,0.5,1", help="comma-separated payloads (kg)")
    p.add_argument("--controllers", default="usual,first,second")
    p.add_argument("--tunings", default="paper,stiff", help=f"comma-separated names of {sorted(TUNINGS)}")
    p.add_argument("--hold", type=float, default=2.0, help="hold after the path (s)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (default: a LocalCluster)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    p.add_argument("--out", default="sweep-out", help="output folder: sweep.csv, sweep.png")
    args = p.parse_args()

    from dask.distributed import Client, LocalCluster

    points = grid(
        [float(v) for v in args.payloads.split(",")],
        [k.strip() for k in args.controllers.split(",")],
        {name: TUNINGS[name] for name in args.tunings.split(",")},
        base={"simulation": {"hold_s": args.hold}},
    )
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if args.scheduler:
        client = Client(args.scheduler)
        cluster = None
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    t_cluster = time.perf_counter() - t0
    try:
        t1 = time.perf_counter()
        rows = run_sweep(client, points)
        t_sweep = time.perf_counter() - t1
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    print(write_table(rows, out / "sweep.csv"))
    write_figure(rows, out / "sweep.png")
    busy = sum(r["task_s"] for r in rows)
    print(
        f"{len(rows)} points in {t_sweep:.2f} s on the cluster (sum of task times {busy:.2f} s; "
        f"cluster start {t_cluster:.2f} s); {out}/sweep.csv, {out}/sweep.png"
    )


if __name__ == "__main__":
    main()
