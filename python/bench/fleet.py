"""A fleet of simulated logs fitted four ways, timed in one run (issue 43's benchmark).

    python python/bench/fleet.py [--logs 200] [--kind flight|sweep] [--repeats 3]

Needs the package installed from this checkout with its release profile
(``pip install ./python``), ``dask[distributed]``, and the release binary
(``cargo build --release``; ``MRSYSID_BIN`` overrides its path). It simulates the logs
once into ``--dir`` (default: a temporary directory), then times, fastest of
``--repeats``:

- ``cli``: ``mrsysid fit LOGS --threads 2 --no-diagnose --quiet``, one process;
- ``cli+diagnosis``: the same with the diagnosis (the reference the issue names);
- ``dask``: ``mrsysid.dask.fit_fleet(diagnose=False)`` on a two-worker
  ``LocalCluster`` (one thread each, started before the clock), which reads the logs
  into statistics parts on the workers and fits on the client;
- ``dask+diagnosis``: ``fit_fleet`` with the diagnosis: the second pass and the
  remainder pass as tasks on the workers, the diagnosis on the client.

and checks that the Dask fits equal the CLI's: the estimates without the diagnosis
(relative 1e-12), the whole JSON report with it.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
VEHICLE = ROOT / "data" / "vehicles" / "quad_x.toml"


def binary() -> str:
    return os.environ.get("MRSYSID_BIN", str(ROOT / "target" / "release" / "mrsysid"))


def simulate(directory: Path, logs: int, kind: str) -> list:
    """`logs` logs of `kind` (20 s flights at 100 Hz, or 1000-point sweeps), seeds 1..N."""
    directory.mkdir(parents=True, exist_ok=True)

    def one(k: int) -> Path:
        path = directory / f"{kind}-{k:04d}.csv"
        if not path.exists():
            shape = (
                ["--mode", "flight", "--duration", "20", "--log-rate", "100"]
                if kind == "flight"
                else ["--mode", "sweep", "--points", "1000"]
            )
            subprocess.run(
                [binary(), "simulate", "--vehicle", str(VEHICLE), *shape, "--seed", str(k),
                 "--out", str(path)],
                check=True,
                capture_output=True,
            )
        return path

    with ThreadPoolExecutor(max_workers=2) as pool:
        return list(pool.map(one, range(1, logs + 1)))


def fastest(repeats: int, run) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=int, default=200)
    parser.add_argument("--kind", choices=["flight", "sweep"], default="flight")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--dir", type=Path, default=None)
    args = parser.parse_args()

    import distributed

    import mrsysid
    from mrsysid.dask import fit_fleet

    directory = args.dir or Path(tempfile.mkdtemp(prefix="mrsysid-fleet-"))
    logs = simulate(directory, args.logs, args.kind)
    report = directory / "cli.json"

    def cli(*extra: str) -> None:
        subprocess.run(
            [binary(), "fit", *map(str, logs), "--vehicle", str(VEHICLE), "--threads", "2",
             "--quiet", *extra],
            check=True,
        )

    cli_report = directory / "cli-diagnosis.json"
    times = {
        "cli": fastest(args.repeats, lambda: cli("--no-diagnose", "--json", str(report))),
        "cli+diagnosis": fastest(args.repeats, lambda: cli("--json", str(cli_report))),
    }
    cli_estimates = {p["name"]: p["estimate"] for p in json.loads(report.read_text())["parameters"]}
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        client.run(lambda: __import__("mrsysid"))  # workers import the package first
        fleets = {}

        def dask(diagnose: bool):
            def run() -> None:
                fleets[diagnose] = fit_fleet(logs, VEHICLE, client=client, diagnose=diagnose)

            return run

        times["dask"] = fastest(args.repeats, dask(False))
        times["dask+diagnosis"] = fastest(args.repeats, dask(True))
    for fleet in fleets.values():
        assert not fleet.failed, fleet.failed
    worst = max(
        abs(row.estimate - cli_estimates[name]) / max(abs(cli_estimates[name]), 1e-300)
        for name, row in fleets[False].results.parameters.iterrows()
    )
    cli_diagnosed = json.loads(cli_report.read_text())
    dask_diagnosed = fleets[True].results.report()
    differing = sorted(k for k in cli_diagnosed if cli_diagnosed[k] != dask_diagnosed.get(k))
    added = [e["name"] for e in dask_diagnosed["diagnosis"]["effects_added"]]
    print(f"{args.logs} {args.kind} logs in {directory}, fastest of {args.repeats}, "
          f"load average {os.getloadavg()[0]:.1f}, mrsysid {mrsysid.__version__}")
    for name, t in times.items():
        print(f"  {name:<15} {t:7.2f} s   {t / times['cli']:5.2f} x cli")
    print(f"  dask+diagnosis vs cli+diagnosis: {times['dask+diagnosis'] / times['cli+diagnosis']:.2f} x")
    print(f"  largest relative difference of the estimates, dask vs cli: {worst:.1e}")
    print(f"  report fields of dask+diagnosis that differ from the CLI's: {differing or 'none'}")
    print(f"  effects added: {added}")
    if worst > 1e-12 or differing:
        sys.exit("the Dask fits differ from the CLI's")


if __name__ == "__main__":
    main()
