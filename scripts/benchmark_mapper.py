#!/usr/bin/python3
"""Benchmark of the mapper (MRPT RBPF) on bags recorded from the simulator.

For each world: records a bag with `record_simulation_bag` (the simulator's core driving a reactive wander; only
when the bag is not there yet), maps it with `map_from_bag --environment` (as fast as the CPU allows) and prints
the map quality against the rendered ground truth (free-space IoU after aligning by the final map -> world
transform, walls within 2 cells), the trajectory RMSE and the offline speed factor. Exit code 1 when a world
misses a target (IoU >= 0.90, speed >= 5x real time).

    scripts/benchmark_mapper.py [--worlds A.xml,B.xml] [--seconds 300] [--bag-dir DIR] [--seed 0]
"""
import argparse
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
SHARED = os.environ.get("HIDDEN_ROOMS_SHARED_DIR", os.path.join(os.path.dirname(ROOT), "shared"))
DEFAULT_WORLDS = [
    os.path.join(ROOT, "worlds", "small_1.xml"),
    os.path.join(ROOT, "worlds", "medium_1.xml"),
    os.path.join(SHARED, "data", "environments", "office", "OfficePlan.xml"),
]
TARGET_IOU = 0.90
TARGET_SPEED = 5.0


def find_tool(name):
    """The built tool: the workspace's devel space (rospack / catkin_find), else PATH."""
    try:
        out = subprocess.run(["catkin_find", "--first-only", "hidden_rooms", name], capture_output=True, text=True)
        if out.returncode == 0 and out.stdout.strip():
            return out.stdout.strip().splitlines()[0]
    except FileNotFoundError:
        pass
    return name


def parse(output):
    figures = {}
    for line in output.splitlines():
        key, sep, value = line.partition(": ")
        if sep:
            try:
                figures[key.strip()] = float(value)
            except ValueError:
                figures[key.strip()] = value.strip()
    return figures


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--worlds", help="comma-separated environment XMLs (default: small_1, medium_1, OfficePlan)")
    parser.add_argument("--seconds", type=float, default=300.0, help="simulated seconds per bag")
    parser.add_argument("--bag-dir", default="/tmp/hidden_rooms_mapper_benchmark", help="where bags and maps go")
    parser.add_argument("--seed", type=int, default=0, help="seed of the simulation and of the filter")
    parser.add_argument("--config", help="MRPT ini (default: the package's config/rbpf.ini)")
    args = parser.parse_args()

    worlds = args.worlds.split(",") if args.worlds else DEFAULT_WORLDS
    os.makedirs(args.bag_dir, exist_ok=True)
    record, map_from_bag = find_tool("record_simulation_bag"), find_tool("map_from_bag")
    rows, failed = [], False
    for world in worlds:
        if not os.path.isfile(world):
            print("benchmark_mapper: skipping %s (not found)" % world, file=sys.stderr)
            continue
        name = os.path.splitext(os.path.basename(world))[0]
        bag = os.path.join(args.bag_dir, "%s_%gs_seed%d.bag" % (name, args.seconds, args.seed))
        if not os.path.isfile(bag):
            print("recording %s (%g simulated seconds) ..." % (bag, args.seconds), file=sys.stderr)
            subprocess.run([record, world, "--out", bag, "--seconds", str(args.seconds), "--seed", str(args.seed)],
                           check=True, stdout=subprocess.DEVNULL)
        command = [map_from_bag, bag, "--out", os.path.join(args.bag_dir, name + "_map"), "--quiet",
                   "--seed", str(args.seed), "--environment", world]
        if args.config:
            command += ["--config", args.config]
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            print("benchmark_mapper: map_from_bag failed on %s:\n%s" % (bag, result.stderr), file=sys.stderr)
            failed = True
            continue
        figures = parse(result.stdout)
        figures["world"] = name
        rows.append(figures)
        failed |= figures["free_iou"] < TARGET_IOU or figures["speed_factor"] < TARGET_SPEED

    print("| world | bag s | scans inserted | free IoU | walls within 2 cells | wall dist. mean (cells) "
          "| RMSE (m) | max (m) | yaw RMSE (rad) | speed (x real time) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for f in rows:
        print("| %s | %.0f | %d | %.3f | %.3f | %.2f | %.3f | %.3f | %.4f | %.1f |" % (
            f["world"], f["bag_seconds"], f["scans_inserted"], f["free_iou"], f["walls_within_2_cells"],
            f["wall_distance_mean_cells"], f["trajectory_rmse_m"], f["trajectory_max_m"], f["yaw_rmse_rad"],
            f["speed_factor"]))
    print("targets: free IoU >= %.2f, speed >= %gx: %s" % (TARGET_IOU, TARGET_SPEED, "missed" if failed else "met"))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
