#!/usr/bin/python3
"""Snapshots of the package's outputs, to show that a change (a restructuring, a clean-up) changes none of them.

    scripts/output_snapshot.py take WS OUT --shared SHARED [--jobs 2]
    scripts/output_snapshot.py compare A B

`take` runs a fixed, seeded set of commands with the build of the catkin workspace WS (its devel space and the
checkout its src/hidden_rooms links to) and writes what they produce under OUT, with wall-clock figures removed:
  bench/ENV/CASE/METHOD/   predict_rooms_offline on every valid case of SHARED/data/closed_door_benchmark with
                           every method (rooms.png, rooms.yaml, map.yaml, map.pgm, overlay.png, metrics.yaml)
  batch/                   batch_analysis on five environments, 2 batches, up to 8 closed doors, every method,
                           seed 0: results.csv (timing columns dropped, rows sorted) and every case's files
  mapper/                  benchmark_mapper.py on worlds/medium_1.xml, 300 s, seed 0: the bag and the map
  sim/                     benchmark_simulation worlds/large_2.xml, 300 s, seed 1 (timing keys dropped)
`compare` compares two snapshots file by file, prints each file that differs or is missing and a summary line,
and exits 1 when anything differs. Take both snapshots on the same machine: the bytes are those of its
libraries (OpenCV, MRPT, Box2D).
"""
import argparse
import concurrent.futures
import csv
import filecmp
import os
import re
import shlex
import subprocess
import sys

METHODS = ["default", "skewnormal", "structured", "thesis", "unstructured"]
BATCH_ENVIRONMENTS = ["school/Borchen4.xml", "office/Milano-1.xml", "office/magenta.xml", "school/Sabadell1.xml",
                      "office/OfficePlan.xml"]
SIM_TIMING_KEYS = re.compile(r"^(load_seconds|  build_seconds|  realtime_factor):")


class SnapshotError(Exception):
    pass


def run(ws, command, log_path):
    """Runs `command` (a list) with WS's setup.bash sourced; raises SnapshotError naming its log on failure."""
    script = 'source "$1/devel/setup.bash" && shift && exec "$@"'
    with open(log_path, "w") as log:
        status = subprocess.call(["bash", "-c", script, "bash", ws] + command, stdout=log, stderr=subprocess.STDOUT)
    if status != 0:
        raise SnapshotError("%s exited with %d (see %s)" % (shlex.join(command), status, log_path))


def without_lines(path, pattern):
    with open(path) as stream:
        lines = [line for line in stream if not pattern.search(line)]
    with open(path, "w") as stream:
        stream.writelines(lines)


def take_bench(ws, bin_dir, bench_dir, out, logs, jobs):
    with open(os.path.join(bench_dir, "cases.csv"), newline="") as stream:
        cases = [(row["env"], row["case"]) for row in csv.DictReader(stream) if row["valid"] == "1"]
    if not cases:
        raise SnapshotError("%s/cases.csv lists no valid case" % bench_dir)

    def predict(env, case, method):
        case_dir = os.path.join(bench_dir, env, case)
        out_dir = os.path.join(out, "bench", env, case, method)
        run(ws, [os.path.join(bin_dir, "predict_rooms_offline"), "--map", os.path.join(case_dir, "map.yaml"),
                 "--doors", os.path.join(case_dir, "doors.yaml"), "--method", method,
                 "--gt-rooms", os.path.join(case_dir, "gt_rooms.png"), "--out", out_dir],
            os.path.join(logs, "bench_%s_%s_%s.log" % (env, case, method)))
        without_lines(os.path.join(out_dir, "rooms.yaml"), re.compile(r"^\s*(- )?seconds:"))

    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(predict, env, case, method) for env, case in cases for method in METHODS]
        for future in futures:
            future.result()
    return len(futures)


def take_batch(ws, bin_dir, checkout, environments_dir, out, logs, jobs):
    batch = os.path.join(out, "batch")
    run(ws, [os.path.join(checkout, "scripts", "batch_analysis"), "--env"]
        + [os.path.join(environments_dir, name) for name in BATCH_ENVIRONMENTS]
        + ["--batches", "2", "--max-closed", "8", "--methods", ",".join(METHODS), "--seed", "0",
           "--jobs", str(jobs), "--no-progress", "--keep-cases", "--binary", os.path.join(bin_dir, "batch_cases"),
           "--out", batch], os.path.join(logs, "batch.log"))
    # Rows come in the order they finish; the timing columns are wall-clock.
    results = os.path.join(batch, "results.csv")
    with open(results, newline="") as stream:
        rows = list(csv.reader(stream))
    keep = [i for i, name in enumerate(rows[0]) if not (name.startswith("seconds_") or name == "case_seconds")]
    with open(results, "w", newline="") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow([rows[0][i] for i in keep])
        writer.writerows(sorted([row[i] for i in keep] for row in rows[1:]))


def take_mapper(ws, checkout, out, logs):
    run(ws, [os.path.join(checkout, "scripts", "benchmark_mapper.py"), "--worlds",
             os.path.join(checkout, "worlds", "medium_1.xml"), "--seconds", "300", "--seed", "0",
             "--bag-dir", os.path.join(out, "mapper")], os.path.join(logs, "mapper.log"))


def take_sim(ws, bin_dir, checkout, out, logs):
    sim = os.path.join(out, "sim")
    os.makedirs(sim)
    log = os.path.join(logs, "sim.log")
    run(ws, [os.path.join(bin_dir, "benchmark_simulation"), os.path.join(checkout, "worlds", "large_2.xml"),
             "--sim-seconds", "300", "--seed", "1"], log)
    kept, in_timing_block = [], False
    with open(log) as stream:
        for line in stream:
            if line.startswith("scan_microseconds_median:"):
                in_timing_block = True
                continue
            if in_timing_block and line.startswith("  "):
                continue
            in_timing_block = False
            if not SIM_TIMING_KEYS.match(line) and not line.startswith("world:"):
                kept.append(line)
    with open(os.path.join(sim, "benchmark_simulation.yaml"), "w") as stream:
        stream.writelines(kept)


def take(args):
    ws = os.path.realpath(args.ws)
    bin_dir = os.path.join(ws, "devel", "lib", "hidden_rooms")
    package_xml = os.path.join(ws, "src", "hidden_rooms", "package.xml")
    if not os.path.isfile(os.path.join(bin_dir, "predict_rooms_offline")) or not os.path.exists(package_xml):
        raise SnapshotError("%s is no built hidden_rooms workspace (run scripts/setup.sh)" % args.ws)
    checkout = os.path.dirname(os.path.realpath(package_xml))
    bench_dir = os.path.join(args.shared, "data", "closed_door_benchmark")
    environments_dir = os.path.join(args.shared, "data", "environments")
    if not os.path.isdir(bench_dir) or not os.path.isdir(environments_dir):
        raise SnapshotError("%s holds no data/closed_door_benchmark and data/environments" % args.shared)
    if args.jobs < 1:
        raise SnapshotError("--jobs must be at least 1")
    if os.path.exists(args.out) and os.listdir(args.out):
        raise SnapshotError("%s is not empty" % args.out)
    out = os.path.realpath(args.out)
    logs = out + ".logs"  # beside the snapshot, so that compare sees outputs only
    os.makedirs(out, exist_ok=True)
    os.makedirs(logs, exist_ok=True)
    runs = take_bench(ws, bin_dir, bench_dir, out, logs, args.jobs)
    take_batch(ws, bin_dir, checkout, environments_dir, out, logs, args.jobs)
    take_mapper(ws, checkout, out, logs)
    take_sim(ws, bin_dir, checkout, out, logs)
    files = sum(len(names) for _, _, names in os.walk(out))
    print("%s: %d predictions, a batch analysis, a mapping run and a simulation: %d files (logs in %s)"
          % (out, runs, files, logs))
    return 0


def relative_files(root):
    return {os.path.relpath(os.path.join(folder, name), root) for folder, _, names in os.walk(root) for name in names}


def compare(args):
    for folder in (args.a, args.b):
        if not os.path.isdir(folder):
            raise SnapshotError("%s is no folder" % folder)
    a, b = relative_files(args.a), relative_files(args.b)
    missing = sorted(a ^ b)
    different = sorted(name for name in a & b
                       if not filecmp.cmp(os.path.join(args.a, name), os.path.join(args.b, name), shallow=False))
    for name in missing:
        print("MISSING in %s: %s" % ("B" if name in a else "A", name))
    for name in different:
        print("DIFFERENT %s" % name)
    print("identical: %d files, different: %d, missing: %d" % (len(a & b) - len(different), len(different),
                                                                len(missing)))
    return 1 if missing or different else 0


def main():
    parser = argparse.ArgumentParser(prog="output_snapshot.py", description=__doc__.split("\n\n")[0])
    verbs = parser.add_subparsers(dest="verb", required=True)
    take_parser = verbs.add_parser("take", help="run the commands of a build and keep their outputs")
    take_parser.add_argument("ws", metavar="WS", help="a built catkin workspace (e.g. .ws)")
    take_parser.add_argument("out", metavar="OUT", help="snapshot folder (new or empty)")
    take_parser.add_argument("--shared", required=True, help="the shared data folder (holds data/)")
    take_parser.add_argument("--jobs", type=int, default=2, help="commands run side by side")
    compare_parser = verbs.add_parser("compare", help="compare two snapshots file by file")
    compare_parser.add_argument("a", metavar="A")
    compare_parser.add_argument("b", metavar="B")
    args = parser.parse_args()
    try:
        return take(args) if args.verb == "take" else compare(args)
    except SnapshotError as error:
        print("output_snapshot.py: error: %s" % error, file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
