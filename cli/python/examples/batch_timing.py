"""The time a batch of generated plans takes through Ray on this machine,
against a plain loop over the CLI, both writing an EXR per plan.

    python3 cli/python/examples/batch_timing.py [--plans 32] [--repeat 3] [--spp 16] [--scale 0.5]

Prints the median of each and their ratio. The CLI is `FLATRAY_BIN`, or
this checkout's release build.
"""

import argparse
import os
import pathlib
import statistics
import subprocess
import tempfile
import time

import ray

import flatray
from flatray import batch

REPO = pathlib.Path(__file__).resolve().parents[3]
CLI = os.environ.get("FLATRAY_BIN", str(REPO / "target" / "release" / "flatray"))
SETTINGS = dict(rooms=4, lamps=1, spp=16, bounces=1, scale=0.5)


def cli_loop(seeds, folder):
    for seed in seeds:
        plan = folder / f"plan-{seed}.ron"
        subprocess.run([CLI, "generate", "--rooms", str(SETTINGS["rooms"]), "--lamps",
                        str(SETTINGS["lamps"]), "--seed", str(seed), "-o", str(plan), "--force"],
                       check=True, capture_output=True)
        subprocess.run([CLI, "render", str(plan), "-o", str(folder / f"plan-{seed}.exr"), "-q",
                        "--spp", str(SETTINGS["spp"]), "--bounces", str(SETTINGS["bounces"]),
                        "--scale", str(SETTINGS["scale"])], check=True, capture_output=True)


def ray_batch(seeds, folder):
    batch.render_generated(seeds, folder, rooms=SETTINGS["rooms"], lamps=SETTINGS["lamps"],
                           spp=SETTINGS["spp"], bounces=SETTINGS["bounces"],
                           scale=SETTINGS["scale"])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--plans", type=int, default=32)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--spp", type=int, default=SETTINGS["spp"])
    parser.add_argument("--scale", type=float, default=SETTINGS["scale"])
    args = parser.parse_args()
    SETTINGS.update(spp=args.spp, scale=args.scale)
    ray.init(include_dashboard=False, log_to_driver=False)
    seeds = list(range(args.plans))
    times = {"cli": [], "ray": []}
    with tempfile.TemporaryDirectory() as tmp:
        ray_batch(seeds[:2], pathlib.Path(tmp) / "warm")  # workers started
        for k in range(args.repeat):
            for name, run in [("cli", cli_loop), ("ray", ray_batch)]:
                folder = pathlib.Path(tmp) / f"{name}-{k}"
                folder.mkdir()
                started = time.perf_counter()
                run(seeds, folder)
                times[name].append(time.perf_counter() - started)
    cli, through_ray = statistics.median(times["cli"]), statistics.median(times["ray"])
    print(f"{args.plans} plans ({SETTINGS}), {os.cpu_count()} cores")
    print(f"CLI loop: median {cli:.2f} s of {times['cli']}")
    print(f"Ray:      median {through_ray:.2f} s of {times['ray']}")
    print(f"Ray / CLI: {through_ray / cli:.2f}")


if __name__ == "__main__":
    main()
