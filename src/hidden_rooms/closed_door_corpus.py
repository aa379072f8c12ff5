"""Closed-door cases from the package's own explorations (docs/tools.md#make_closed_door_corpus).

Two stages:

- `explore`: one offline exploration per environment (`explore_offline`: simulator, SLAM mapper and explorer in
  one process, every door open), scored by `translate_doors`, kept in a store folder: the explored map
  (`map.yaml` + compressed `map.png`), every closable door in the map frame with the transform that carried it
  over (`doors.yaml`), the run (`run.yaml`) and its score (`exploration.yaml`). Expensive (minutes per
  environment), resumable, seeded, deterministic; the repository keeps the store in data/closed_door_corpus.
- `cases`: per stored environment, a seeded order of its closable doors and case k = the first k closed: the
  rooms behind them erased from the explored map as a robot would miss them (walls seen from explored rooms
  kept), the doors painted as walls (`batch_cases --write-cases`). Doors whose room the explored map does not
  show are left out of the order. Written in the closed-door benchmark's layout
  (ENV/NN_doors/{map.yaml, map.pgm, doors.yaml, gt_rooms.png} and cases.csv), in seconds.
"""
import concurrent.futures
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile

import yaml
from tqdm import tqdm

from hidden_rooms.batch_analysis import door_sequence
from hidden_rooms.package_tools import ArgumentParser, REPO_DIR, ToolError, find_binary, tool_error

STORE_FILES = ("map.yaml", "map.png", "doors.yaml", "run.yaml", "exploration.yaml")
SPLIT_FILE = "split.csv"
CASE_COLUMNS = ["env", "case", "closed_doors_nominal", "doors_found", "valid", "hidden_rooms", "hidden_pct",
                "reference_iou", "kind", "part", "door_ids", "min_room_coverage", "unmapped_rooms"]
# A case is scored only when the explored map shows each hidden room: its area in the map at least this share
# of its free area in the rendering.
MIN_ROOM_COVERAGE = 0.8


class CorpusError(ToolError):
    """Bad arguments or input (exit code 2)."""


def environment_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def read_split(store):
    """{env: (kind, part)} from STORE/split.csv (empty when there is none)."""
    path = os.path.join(store, SPLIT_FILE)
    if not os.path.isfile(path):
        return {}
    with open(path, newline="") as stream:
        return {row["env"]: (row["kind"], row["part"]) for row in csv.DictReader(stream)}


# --------------------------------------------------------------------------------------------------------
# explore


def explored_dir(store, name):
    return os.path.join(store, "explored", name)


def has_run(store, name):
    """True when the store holds every file of a run of `name`."""
    return all(os.path.isfile(os.path.join(explored_dir(store, name), f)) for f in STORE_FILES)


def run_tool(command, what):
    """Runs one of the package's tools; returns its stdout, raises CorpusError with its message when it fails."""
    result = subprocess.run(command, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    if result.returncode != 0:
        raise CorpusError("%s: %s" % (what, tool_error(result, what)))
    return result.stdout


def explore_and_score(binaries, path, out, seed, max_time, config, closed=""):
    """explore_offline of one environment into `out`, scored by translate_doors into `out`/score."""
    run_tool([binaries["explore_offline"], path, "--config", config, "--out", out, "--closed", closed, "--seed",
              str(seed), "--max-time", str(max_time), "--pose-period", "0.5", "--quiet"], "explore_offline")
    run_tool([binaries["translate_doors"], "--environment", path, "--closed", closed, "--truth",
              os.path.join(out, "truth.log"), "--estimate", os.path.join(out, "estimate.log"), "--map",
              os.path.join(out, "map.yaml"), "--out", os.path.join(out, "score")], "translate_doors")


def default_config(args):
    return os.path.abspath(args.config or os.path.join(REPO_DIR, "config", "rbpf.ini"))


def is_explored(store, name, settings):
    """True when the store holds a complete run of `name` made with these settings."""
    folder = explored_dir(store, name)
    if not has_run(store, name):
        return False
    with open(os.path.join(folder, "run.yaml")) as stream:
        run = yaml.safe_load(stream) or {}
    return run.get("seed") == settings["seed"] and float(run.get("max_time", -1)) == settings["max_time"]


def explore_one(path, store, settings, binaries):
    """Explores one environment into a temporary folder and moves the kept files into the store at once."""
    name = environment_name(path)
    work = tempfile.mkdtemp(prefix="corpus_%s_" % name)
    try:
        try:
            explore_and_score(binaries, path, work, settings["seed"], settings["max_time"], settings["config"])
        except CorpusError as error:
            return name, str(error)
        with open(os.path.join(work, "run.yaml"), "a") as run:
            run.write("max_time: %s\n" % settings["max_time"])
        shutil.copy(os.path.join(work, "score", "exploration.yaml"), os.path.join(work, "exploration.yaml"))
        staging = explored_dir(store, name) + ".partial"
        shutil.rmtree(staging, ignore_errors=True)
        os.makedirs(staging)
        for file_name in STORE_FILES:
            shutil.copy(os.path.join(work, file_name), os.path.join(staging, file_name))
        shutil.rmtree(explored_dir(store, name), ignore_errors=True)
        os.rename(staging, explored_dir(store, name))
        return name, None
    finally:
        shutil.rmtree(work, ignore_errors=True)


def explore(args):
    paths = [os.path.abspath(path) for path in args.environments]
    for path in paths:
        if not os.path.isfile(path):
            raise CorpusError("%s: no such environment file" % path)
    names = [environment_name(path) for path in paths]
    if len(set(names)) != len(names):
        raise CorpusError("two environments have the same file name; the store keys them by name")
    binaries = {name: find_binary(name) for name in ("explore_offline", "translate_doors")}
    settings = {"seed": args.seed, "max_time": float(args.max_time), "config": default_config(args)}
    os.makedirs(os.path.join(args.store, "explored"), exist_ok=True)
    pending = [path for path in paths if not is_explored(args.store, environment_name(path), settings)]
    print("make_closed_door_corpus: %d environments, %d already explored, %d to explore (%d jobs)" % (
        len(paths), len(paths) - len(pending), len(pending), args.jobs))
    failures = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(explore_one, path, args.store, settings, binaries) for path in pending]
        with tqdm(total=len(futures), unit="env", file=sys.stderr, disable=args.no_progress) as progress:
            for future in concurrent.futures.as_completed(futures):
                name, problem = future.result()
                if problem:
                    failures.append((name, problem))
                    tqdm.write("%s: %s" % (name, problem), file=sys.stderr)
                progress.update(1)
    print_store_summary(args.store, names)
    return 1 if failures else 0


def print_store_summary(store, names):
    print("%-40s %9s %8s %9s %9s %8s %6s" % ("environment", "stop", "sim s", "wall s", "coverage", "free IoU",
                                            "doors"))
    for name in names:
        folder = explored_dir(store, name)
        if not os.path.isfile(os.path.join(folder, "exploration.yaml")):
            print("%-40s %9s" % (name, "missing"))
            continue
        with open(os.path.join(folder, "run.yaml")) as stream:
            run = yaml.safe_load(stream)
        with open(os.path.join(folder, "exploration.yaml")) as stream:
            score = yaml.safe_load(stream)
        with open(os.path.join(folder, "doors.yaml")) as stream:
            doors = len(yaml.safe_load(stream)["doors"] or [])
        print("%-40s %9s %8.0f %9.0f %9.3f %8.3f %6d" % (name, run["stop"], run["simulated_seconds"],
                                                        run["wall_seconds"], score["coverage"], score["free_iou"],
                                                        doors))


# --------------------------------------------------------------------------------------------------------
# cases


def find_environment_files(roots):
    """{name: path} of every *.xml under the given folders (recursively)."""
    found = {}
    for root in roots:
        if not os.path.isdir(root):
            raise CorpusError("%s: no such folder" % root)
        for folder, _, files in os.walk(root):
            for file_name in files:
                if file_name.endswith(".xml"):
                    found.setdefault(environment_name(file_name), os.path.join(folder, file_name))
    return found


def batch_cases(binary, name, xml_path, folder, sequence, extra):
    """batch_cases on the explored map of `folder`; returns its JSON lines."""
    stdout = run_tool([binary, xml_path, "--sequence", ",".join(map(str, sequence)), "--map",
                       os.path.join(folder, "map.yaml"), "--doors-in-map", os.path.join(folder, "doors.yaml")] + extra,
                      "%s: batch_cases" % name)
    return [json.loads(line) for line in stdout.splitlines()]


def mapped_doors(binary, name, xml_path, folder):
    """The closable doors whose room the explored map shows (at least MIN_ROOM_COVERAGE of it), and all of them."""
    with open(os.path.join(folder, "doors.yaml")) as stream:
        closable = sorted(int(door["id"]) for door in yaml.safe_load(stream)["doors"] or [])
    if not closable:
        return [], []
    # All closed at once: room_coverage lists the doors in number order.
    everything = batch_cases(binary, name, xml_path, folder, closable, ["--cases", str(len(closable))])[-1]
    return [door for door, coverage in zip(closable, everything["room_coverage"])
            if coverage >= MIN_ROOM_COVERAGE], closable


def cases_of_environment(name, xml_path, store, out, settings, binary):
    """Writes the cases of one environment under OUT/name; returns its cases.csv rows."""
    folder = explored_dir(store, name)
    eligible, closable = mapped_doors(binary, name, xml_path, folder)
    if not eligible:
        return []
    sequence = door_sequence(settings["seed"], name, 0, eligible, settings["max_closed"])
    work = tempfile.mkdtemp(prefix="corpus_cases_%s_" % name)
    try:
        lines = batch_cases(binary, name, xml_path, folder, sequence, ["--write-cases", work])
        kind, part = settings["split"].get(name, ("", ""))
        rows = []
        target_root = os.path.join(out, name)
        shutil.rmtree(target_root, ignore_errors=True)
        for case in lines:
            k = case["closed_doors"]
            case_name = "%02d_doors" % k
            source, target = os.path.join(work, "%d_doors" % k), os.path.join(target_root, case_name)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            shutil.move(source, target)
            os.rename(os.path.join(target, "true_rooms.png"), os.path.join(target, "gt_rooms.png"))
            coverage = min(case["room_coverage"])
            rows.append({"env": name, "case": case_name, "closed_doors_nominal": k, "doors_found": k,
                         "valid": int(coverage >= MIN_ROOM_COVERAGE), "hidden_rooms": k,
                         "hidden_pct": "%.2f" % case["hidden_percent"], "reference_iou": "", "kind": kind,
                         "part": part, "door_ids": " ".join(map(str, case["door_ids"])),
                         "min_room_coverage": "%.3f" % coverage, "unmapped_rooms": len(closable) - len(eligible)})
        return rows
    finally:
        shutil.rmtree(work, ignore_errors=True)


def cases(args):
    split = read_split(args.store)
    explored = sorted(name for name in os.listdir(os.path.join(args.store, "explored")) if has_run(args.store, name))
    if args.part:
        explored = [name for name in explored if split.get(name, ("", ""))[1] == args.part]
    if not explored:
        raise CorpusError("%s holds no explored environment%s" % (
            args.store, " of part %s" % args.part if args.part else ""))
    xml_files = find_environment_files(args.environments_dir)
    missing = [name for name in explored if name not in xml_files]
    if missing:
        raise CorpusError("no environment file for %s under %s" % (", ".join(missing), ", ".join(args.environments_dir)))
    binary = find_binary("batch_cases")
    settings = {"seed": args.seed, "max_closed": args.max_closed, "split": split}
    os.makedirs(args.out, exist_ok=True)
    rows = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {name: pool.submit(cases_of_environment, name, xml_files[name], args.store, args.out, settings,
                                     binary) for name in explored}
        for name in explored:
            rows += futures[name].result()
    staging = os.path.join(args.out, "cases.csv.partial")
    with open(staging, "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=CASE_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    os.replace(staging, os.path.join(args.out, "cases.csv"))
    valid = sum(row["valid"] for row in rows)
    print("make_closed_door_corpus: %d cases of %d environments (%d valid: every hidden room mapped to at least "
          "%.0f%% of its area) -> %s" % (len(rows), len(explored), valid, 100 * MIN_ROOM_COVERAGE,
                                            os.path.join(args.out, "cases.csv")))
    return 0


# --------------------------------------------------------------------------------------------------------
# check: a derived case against a real exploration with the same doors closed


def free_in_world(map_yaml, world_from_map, shape, resolution, origin):
    """Boolean image (world grid of `shape`, `resolution`, lower-left `origin`) of the map's free cells."""
    import cv2
    import numpy as np
    with open(map_yaml) as stream:
        meta = yaml.safe_load(stream)
    image = cv2.imread(os.path.join(os.path.dirname(map_yaml), meta["image"]), cv2.IMREAD_GRAYSCALE)
    free = (image >= 250).astype(np.uint8)
    r, (ox, oy) = meta["resolution"], meta["origin"][:2]
    x, y, yaw = world_from_map
    c, s_ = np.cos(yaw), np.sin(yaw)
    # map pixel (col, row) -> map metres -> world metres -> world pixel
    map_to_metres = np.array([[r, 0, ox + 0.5 * r], [0, -r, oy + (image.shape[0] - 0.5) * r], [0, 0, 1]])
    rotate = np.array([[c, -s_, x], [s_, c, y], [0, 0, 1]])
    metres_to_world = np.array([[1 / resolution, 0, -origin[0] / resolution - 0.5],
                                [0, -1 / resolution, origin[1] / resolution + shape[0] - 0.5], [0, 0, 1]])
    affine = (metres_to_world @ rotate @ map_to_metres)[:2]
    return cv2.warpAffine(free, affine, (shape[1], shape[0]), flags=cv2.INTER_NEAREST) > 0


def check(args):
    """Explores the environment with the doors closed and compares map and prediction with the derived case."""
    import numpy as np
    name = environment_name(args.environment)
    folder = explored_dir(args.store, name)
    if not has_run(args.store, name):
        raise CorpusError("%s is not explored in %s" % (name, args.store))
    doors = [int(door) for door in args.closed.split(",") if door.strip()]
    if not doors:
        raise CorpusError("--closed: no door")
    binaries = {tool: find_binary(tool) for tool in ("explore_offline", "translate_doors", "batch_cases",
                                                       "predict_rooms_offline")}
    work = args.work or tempfile.mkdtemp(prefix="corpus_check_%s_" % name)
    os.makedirs(work, exist_ok=True)

    closed = ",".join(map(str, doors))
    derived_dir = os.path.join(work, "derived")
    derived = batch_cases(binaries["batch_cases"], name, args.environment, folder, doors,
                          ["--cases", str(len(doors)), "--methods", args.method, "--write-cases", derived_dir])[-1]
    derived_map = os.path.join(derived_dir, "%d_doors" % len(doors), "map.yaml")
    real = os.path.join(work, "real")
    explore_and_score(binaries, args.environment, real, args.seed, args.max_time, default_config(args), closed)
    run_tool([binaries["predict_rooms_offline"], "--map", os.path.join(real, "map.yaml"), "--doors",
              os.path.join(real, "score", "doors.yaml"), "--method", args.method, "--gt-rooms",
              os.path.join(real, "score", "true_rooms.png"), "--out", os.path.join(real, "prediction")],
             "predict_rooms_offline")
    with open(os.path.join(real, "prediction", "metrics.yaml")) as stream:
        real_metrics = yaml.safe_load(stream)
    real_ious = [float(room["iou"]) for room in real_metrics["rooms"]]

    # Both maps' known free space, placed in the world by each run's trajectory fit.
    with open(os.path.join(folder, "exploration.yaml")) as stream:
        open_fit = yaml.safe_load(stream)["world_from_map"]
    with open(os.path.join(real, "score", "exploration.yaml")) as stream:
        real_fit = yaml.safe_load(stream)["world_from_map"]
    resolution = 0.05
    corners = []
    for map_yaml, fit in ((derived_map, open_fit), (os.path.join(real, "map.yaml"), real_fit)):
        with open(map_yaml) as stream:
            meta = yaml.safe_load(stream)
        corners.append((meta["origin"][0] + fit[0], meta["origin"][1] + fit[1]))
    origin = (min(c[0] for c in corners) - 20.0, min(c[1] for c in corners) - 20.0)
    shape = (int(240 / resolution), int(240 / resolution))
    derived_free = free_in_world(derived_map, open_fit, shape, resolution, origin)
    real_free = free_in_world(os.path.join(real, "map.yaml"), real_fit, shape, resolution, origin)
    union = np.count_nonzero(derived_free | real_free)
    free_iou = np.count_nonzero(derived_free & real_free) / union if union else 0.0
    print("environment %s, doors %s closed, method %s" % (name, closed, args.method))
    print("  derived case:      mean IoU %.4f  per door %s  free area %.1f m2" % (
        derived["methods"][args.method]["mean_iou"], " ".join("%.3f" % v for v in derived["methods"][args.method]["iou"]),
        np.count_nonzero(derived_free) * resolution ** 2))
    print("  real exploration:  mean IoU %.4f  per door %s  free area %.1f m2" % (
        float(real_metrics["mean_iou"]), " ".join("%.3f" % v for v in real_ious),
        np.count_nonzero(real_free) * resolution ** 2))
    print("  free-space IoU of the two maps (world frame): %.4f" % free_iou)
    print("  outputs in %s" % work)
    return 0


# --------------------------------------------------------------------------------------------------------


def parse_arguments(argv):
    parser = ArgumentParser(prog="make_closed_door_corpus", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    default_store = os.path.join(REPO_DIR, "data", "closed_door_corpus")

    explore_parser = commands.add_parser("explore", help="explore environments into the store (expensive)")
    explore_parser.add_argument("environments", nargs="+", metavar="ENV.xml")
    explore_parser.add_argument("--store", default=default_store, help="store folder (default: %(default)s)")
    explore_parser.add_argument("--seed", type=int, default=0, help="seed of the simulation and the filter")
    explore_parser.add_argument("--max-time", type=float, default=2400.0, help="simulated seconds at most")
    explore_parser.add_argument("--config", help="MRPT ini (default: the package's config/rbpf.ini)")
    explore_parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    explore_parser.add_argument("--no-progress", action="store_true")

    cases_parser = commands.add_parser("cases", help="derive the closed-door cases from the store (seconds)")
    cases_parser.add_argument("--store", default=default_store, help="store folder (default: %(default)s)")
    cases_parser.add_argument("--environments-dir", action="append", required=True, metavar="DIR",
                              help="folder with the environment XML files (searched recursively; repeatable)")
    cases_parser.add_argument("--out", required=True, help="benchmark folder to write")
    cases_parser.add_argument("--part", help="only the environments of this part of split.csv")
    cases_parser.add_argument("--seed", type=int, default=0, help="seed of the door orders")
    cases_parser.add_argument("--max-closed", type=int, default=15, help="doors closed at most per environment")
    cases_parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    check_parser = commands.add_parser("check", help="a derived case against a real exploration with those doors "
                                                     "closed (maps and predictions)")
    check_parser.add_argument("environment", metavar="ENV.xml")
    check_parser.add_argument("--closed", required=True, help="door numbers, comma-separated (closable, explored)")
    check_parser.add_argument("--store", default=default_store, help="store folder (default: %(default)s)")
    check_parser.add_argument("--method", default="default", help="prediction method (default: %(default)s)")
    check_parser.add_argument("--seed", type=int, default=0)
    check_parser.add_argument("--max-time", type=float, default=2400.0)
    check_parser.add_argument("--config", help="MRPT ini (default: the package's config/rbpf.ini)")
    check_parser.add_argument("--work", help="keep the outputs here (default: a temporary folder, kept)")
    args = parser.parse_args(argv)
    if getattr(args, "jobs", 1) < 1:
        parser.error("--jobs must be at least 1")
    if args.command == "cases" and args.max_closed < 1:
        parser.error("--max-closed must be at least 1")
    if args.command == "explore" and args.max_time <= 0:
        parser.error("--max-time must be positive")
    return args


def main(argv=None):
    args = parse_arguments(argv)
    try:
        return {"explore": explore, "cases": cases, "check": check}[args.command](args)
    except ToolError as error:
        print("make_closed_door_corpus: error: %s" % error, file=sys.stderr)
        return 2
