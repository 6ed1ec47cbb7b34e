"""The Dask sweep (examples/python/sweep_dask.py): a 4-point grid on a 2-worker
LocalCluster (processes) gives exactly the numbers of `ofmpc run` for the same
scenarios (every metric but the wall and step times, which are measurements)."""

from __future__ import annotations

import json
import subprocess

import pytest

from conftest import ofmpc_binary

distributed = pytest.importorskip("dask.distributed")
import sweep_dask  # noqa: E402  (examples/python, on sys.path by conftest)

# Measurements, not results: they differ from run to run.
TIMINGS = {"wall_s", "step_time_us", "telemetry"}  # telemetry: machine times


def test_a_4_point_sweep_on_2_workers_equals_the_cli(tmp_path):
    points = sweep_dask.grid(
        payloads=[0.25],
        controllers=["usual", "second"],
        tunings={"paper": {}, "stiff": {"q_dy": 0.25}},
        base={"simulation": {"hold_s": 1.0}},
    )
    assert len(points) == 4
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with distributed.Client(cluster) as client:
            rows = sweep_dask.run_sweep(client, points)
            workers = {w.name for w in cluster.workers.values()}
    assert len(workers) == 2
    sweep_dask.write_table(rows, tmp_path / "sweep.csv")
    sweep_dask.write_figure(rows, tmp_path / "sweep.png")
    assert (tmp_path / "sweep.png").stat().st_size > 10_000

    cli = ofmpc_binary()
    for i, (point, row) in enumerate(zip(points, rows)):
        scenario = tmp_path / f"point{i}.toml"
        scenario.write_text(sweep_dask.scenario_toml(point["scenario"]))
        out = tmp_path / f"out{i}"
        subprocess.run([str(cli), "run", str(scenario), "--out", str(out)], check=True, capture_output=True)
        (expected,) = json.loads((out / "metrics.json").read_text())["runs"]
        got = {k: v for k, v in row.items() if k not in TIMINGS | {"tuning", "task_s"}}
        want = {k: v for k, v in expected.items() if k not in TIMINGS}
        assert got == want, f"grid point {i} ({point['scenario']['title']})"
        assert set(row) - {"tuning", "task_s"} == set(expected), "the same fields as metrics.json"
    # The grid is not degenerate: the tuning changes the second algorithm's result,
    # and the usual MPC keeps its offset while the second removes it.
    by = {(r["controller"], r["tuning"]): r for r in rows}
    assert by[("second", "paper")]["cartesian_error_rms_mm"] != by[("second", "stiff")]["cartesian_error_rms_mm"]
    assert by[("usual", "paper")]["steady_cartesian_error_mm"] > 0.01
    assert by[("second", "paper")]["steady_cartesian_error_mm"] < 1e-6


def test_controller_shorthands_expand_to_one_point_per_controller():
    """Issue #36: controllers=["paper"] made one point of three runs; now three points."""
    points = sweep_dask.grid([0.0], ["paper"], {"paper": {}})
    assert [p["scenario"]["controllers"] for p in points] == [["usual"], ["first"], ["second"]]
    assert len(sweep_dask.grid([0.0], ["all"], {"paper": {}})) == 9
