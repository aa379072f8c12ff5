#!/usr/bin/python3
"""Runs room-prediction methods on a closed-door benchmark folder and compares them with the reference.

Usage: benchmark_closed_doors.py BENCH_DIR --method NAME [--methods A,B,...] [--part P] [--jobs N]
                                 [--binary PATH] [--keep DIR] [--params FILE.yaml] [--csv FILE] [--plot FILE.png]
                                 [--agreement] [--turn DEGREES] [--variant LABEL METHOD PARAMS.yaml]...
                                 [--best-of]

For every valid case of BENCH_DIR/cases.csv it runs `predict_rooms_offline` once per method (in parallel),
times the whole command, reads the per-door IoU from the command's metrics.yaml and computes the thesis
implementation's IoU from reference_rooms.png vs gt_rooms.png where a case has one. It prints a table by number
of closed doors, one per environment, the overall mean IoU per method and of the reference, and the time and
peak memory per method. With --agreement it also compares each method's rooms with the thesis implementation's,
room by room (the IoU of the method's room k with reference_rooms.png's room k; 1 when both are empty), per case
and by number of closed doors, next to the IoU against the truth. Any folder in the benchmark's layout works,
e.g. the cases of make_closed_door_corpus (whose cases.csv has a `part` column: --part validation). With --turn
every case is first turned by that many degrees (map, true rooms and doors), as real SLAM maps are. A --variant
is one more column: METHOD run with the parameter overrides of PARAMS.yaml, printed as LABEL (settings compared
side by side, on the same cases and parts). With --best-of it also prints, per part, the mean IoU the columns
would score together if every door took the room of the column that scores best on it: how much a better choice
among them could gain (for example among the rooms of `default`'s candidates, one variant each).

Peak memory is the maximum resident set size of each command as measured by `/usr/bin/time -f %M` (GNU time),
which wraps every run. resource.getrusage(RUSAGE_CHILDREN) is not used: on Linux a child started by this
Python process inherits the parent's RSS high-water mark through fork/exec, so it would report the size of
this script rather than of the command. Without /usr/bin/time the peak memory is not measured.

Exit codes: 0 all cases ran, 1 some case failed (it is counted with IoU 0), 2 bad arguments or benchmark folder.
"""
import argparse
import concurrent.futures
import csv
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import cv2
import numpy as np
import yaml
from tqdm import tqdm

# The package's Python module, from this checkout (also when the workspace is not sourced).
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.realpath(__file__))), "src"))
from hidden_rooms import package_tools  # noqa: E402

BINARY_NAME = "predict_rooms_offline"
GNU_TIME = "/usr/bin/time"
STDERR_EXCERPT_LINES = 8
MAX_DOORS_ROW = 15
MAX_FAILURES_LISTED = 20


class BenchmarkError(Exception):
    """A problem with the arguments or the benchmark folder (exit code 2)."""


# --------------------------------------------------------------------------------------------------------
# Benchmark folder


class Case:
    """One case of the benchmark: its folder, its doors and the reference score."""

    def __init__(self, row, bench_dir):
        self.env = row["env"]
        self.name = row["case"]
        self.part = (row.get("part") or "").strip()
        self.folder = os.path.join(bench_dir, self.env, self.name)
        self.csv_reference_iou = parse_optional_float(row.get("reference_iou"))
        self.doors, self.doors_problem = read_door_count(os.path.join(self.folder, "doors.yaml"))
        if self.doors is None:
            self.doors = parse_optional_int(row.get("doors_found")) or parse_optional_int(
                row.get("closed_doors_nominal")) or 0
        self.reference_iou = None
        self.reference_problem = None

    @property
    def label(self):
        return "%s/%s" % (self.env, self.name)

    def path(self, name):
        return os.path.join(self.folder, name)


def parse_optional_float(text):
    """A float from a CSV cell, None when the cell is empty."""
    text = (text or "").strip()
    return float(text) if text else None


def parse_optional_int(text):
    """An int from a CSV cell, None when the cell is empty."""
    value = parse_optional_float(text)
    return None if value is None else int(value)


def read_door_count(path):
    """Number of doors in a doors.yaml, and None plus the problem when it cannot be read."""
    try:
        with open(path) as stream:
            data = yaml.safe_load(stream)
        return len(data["doors"]), None
    except (OSError, yaml.YAMLError, TypeError, KeyError) as error:
        return None, "%s: %s" % (path, error)


def load_cases(bench_dir, part=None):
    """The valid cases listed in BENCH_DIR/cases.csv (only those of `part` when given: its `part` column)."""
    csv_path = os.path.join(bench_dir, "cases.csv")
    if not os.path.isdir(bench_dir):
        raise BenchmarkError("benchmark folder %s does not exist" % bench_dir)
    if not os.path.isfile(csv_path):
        raise BenchmarkError("%s is not a closed-door benchmark folder: %s is missing" % (bench_dir, csv_path))
    with open(csv_path, newline="") as stream:
        reader = csv.DictReader(stream)
        missing = {"env", "case", "valid"} - set(reader.fieldnames or [])
        if missing:
            raise BenchmarkError("%s lacks the column(s) %s" % (csv_path, ", ".join(sorted(missing))))
        rows = list(reader)
    cases = [Case(row, bench_dir) for row in rows if (row.get("valid") or "").strip() == "1"]
    if part:
        parts = sorted({case.part for case in cases if case.part})
        cases = [case for case in cases if case.part == part]
        if not cases:
            raise BenchmarkError("%s lists no valid case of part '%s' (its parts: %s)" % (
                csv_path, part, ", ".join(parts) or "none, it has no part column"))
    if not cases:
        raise BenchmarkError("%s lists no valid case" % csv_path)
    return cases


def content_box(image, truth, unknown):
    """(left, top, right, bottom), right and bottom exclusive: the bounding box of the known cells and true rooms
    (the whole image when it has neither)."""
    known = image != unknown
    if known.ndim == 3:
        known = known.any(axis=2)
    rows, columns = np.nonzero(known | (truth > 0))
    if rows.size == 0:
        return 0, 0, image.shape[1], image.shape[0]
    return int(columns.min()), int(rows.min()), int(columns.max()) + 1, int(rows.max()) + 1


def content_margins(image, truth, unknown):
    """Cells between content_box and the image's left, top, right and bottom edges."""
    left, top, right, bottom = content_box(image, truth, unknown)
    return np.array([left, top, image.shape[1] - right, image.shape[0] - bottom])


def turned_case(case, degrees, root):
    """The case turned counter-clockwise by `degrees` about its map's centre, written under ROOT/ENV/CASE: as a SLAM
    map whose frame starts off the building's axes. The map and the true rooms are resampled (nearest cell), unknown
    outside, onto a grid around the turned building with the straight map's margin on each side (a quarter turn
    moves every cell exactly); the doors move with them (their orientation swaps at odd quarter turns); the
    reference rooms are left out. Returns the turned Case."""
    folder = os.path.join(root, case.env, case.name)
    os.makedirs(folder, exist_ok=True)
    with open(case.path("map.yaml")) as stream:
        meta = yaml.safe_load(stream)
    image = cv2.imread(os.path.join(case.folder, meta["image"]), cv2.IMREAD_UNCHANGED)
    truth = read_label_image(case.path("gt_rooms.png"))
    height, width = image.shape[:2]
    turn = cv2.getRotationMatrix2D(((width - 1) / 2.0, (height - 1) / 2.0), degrees, 1.0)
    cos, sin = abs(turn[0, 0]), abs(turn[0, 1])
    new_width = int(np.ceil(width * cos + height * sin - 1e-6))
    new_height = int(np.ceil(width * sin + height * cos - 1e-6))
    turn[0, 2] += (new_width - width) / 2.0
    turn[1, 2] += (new_height - height) / 2.0
    unknown = 205 if image.dtype == np.uint8 else int(205 / 255 * np.iinfo(image.dtype).max)
    quarter_turns = int(round(degrees / 90.0))
    turned_image = cv2.warpAffine(image, turn, (new_width, new_height), flags=cv2.INTER_NEAREST, borderValue=unknown)
    turned_truth = cv2.warpAffine(truth, turn, (new_width, new_height), flags=cv2.INTER_NEAREST, borderValue=0)
    # The grid is then cut as the case's own is: around the turned building (known cells and true rooms) with the
    # margin the straight map has on each side, so that turning changes the angle and not how far the map reaches.
    margins = np.roll(content_margins(image, truth, unknown), -quarter_turns)
    left, top, right, bottom = content_box(turned_image, turned_truth, unknown)
    left, top = max(0, left - int(margins[0])), max(0, top - int(margins[1]))
    right, bottom = min(new_width, right + int(margins[2])), min(new_height, bottom + int(margins[3]))
    cv2.imwrite(os.path.join(folder, "map.png"), turned_image[top:bottom, left:right])
    cv2.imwrite(os.path.join(folder, "gt_rooms.png"), turned_truth[top:bottom, left:right])
    resolution = float(meta["resolution"])
    origin_x, origin_y = float(meta["origin"][0]), float(meta["origin"][1])
    with open(case.path("doors.yaml")) as stream:
        doors = yaml.safe_load(stream)
    for door in doors["doors"]:
        x, y = door["position"]
        # Pixel centres sit at whole coordinates for OpenCV; rows count down from the map's top.
        column, row = (x - origin_x) / resolution - 0.5, height - (y - origin_y) / resolution - 0.5
        new_column, new_row = turn @ np.array([column, row, 1.0])
        door["position"] = [float(origin_x + (new_column + 0.5) * resolution),
                            float(origin_y + (new_height - new_row - 0.5) * resolution)]
        if quarter_turns % 2 and door.get("orientation") in ("O", "V"):
            door["orientation"] = "V" if door["orientation"] == "O" else "O"
    # The cut grid keeps the frame of the whole turned one.
    meta["origin"] = [origin_x + left * resolution, origin_y + (new_height - bottom) * resolution, 0.0]
    with open(os.path.join(folder, "doors.yaml"), "w") as stream:
        yaml.safe_dump(doors, stream)
    meta["image"] = "map.png"
    with open(os.path.join(folder, "map.yaml"), "w") as stream:
        yaml.safe_dump(meta, stream)
    return Case({"env": case.env, "case": case.name, "part": case.part, "valid": "1"}, root)


# --------------------------------------------------------------------------------------------------------
# Reference score


def read_label_image(path):
    """A label image as a 2-D integer array; raises ValueError when it cannot be read."""
    if not os.path.isfile(path):
        raise ValueError("%s is missing" % path)
    image = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError("%s cannot be read" % path)
    if image.ndim != 2:
        raise ValueError("%s is not a single-channel label image" % path)
    return image


def door_ious(predicted, truth, doors, both_empty=0.0):
    """IoU of label k in both images for k = 1..doors (`both_empty` when both are empty)."""
    ious = []
    for label in range(1, doors + 1):
        predicted_room = predicted == label
        true_room = truth == label
        union = np.count_nonzero(predicted_room | true_room)
        intersection = np.count_nonzero(predicted_room & true_room)
        ious.append(intersection / union if union else both_empty)
    return ious


def score_reference(case):
    """Sets case.reference_iou (mean IoU of reference_rooms.png), or case.reference_problem; a case without
    reference_rooms.png (a corpus of the package's own) has neither."""
    if not os.path.exists(case.path("reference_rooms.png")):
        return
    try:
        truth = read_label_image(case.path("gt_rooms.png"))
        reference = read_label_image(case.path("reference_rooms.png"))
        if reference.shape != truth.shape:
            raise ValueError("reference_rooms.png is %dx%d, gt_rooms.png %dx%d" % (
                reference.shape[1], reference.shape[0], truth.shape[1], truth.shape[0]))
        if case.doors <= 0:
            raise ValueError("no doors")
        case.reference_iou = float(np.mean(door_ious(reference, truth, case.doors)))
    except ValueError as error:
        case.reference_problem = str(error)


# --------------------------------------------------------------------------------------------------------
# Running the offline command


def find_binary(explicit=None):
    """Path of predict_rooms_offline: --binary, else $CMAKE_PREFIX_PATH's lib/hidden_rooms, else the repo's .ws."""
    try:
        return package_tools.find_binary(BINARY_NAME, explicit)
    except package_tools.ToolError as error:
        raise BenchmarkError(str(error))


def known_methods(binary):
    """Method names listed by `binary --help` ("Methods: a, b"), or None when they cannot be told."""
    try:
        result = subprocess.run([binary, "--help"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return None
    for line in (result.stdout + result.stderr).splitlines():
        if line.strip().startswith("Methods:"):
            return [name.strip() for name in line.split(":", 1)[1].split(",") if name.strip()]
    return None


class Run:
    """The outcome of one method on one case."""

    def __init__(self, case, method):
        self.case = case
        self.method = method
        self.mean_iou = 0.0
        self.iou_total = 0.0
        self.door_ious = []
        self.agreement = None  # with --agreement and a reference: per door, IoU with reference_rooms.png's room
        self.seconds = None
        self.max_rss_kb = None
        self.problem = None  # None when the run succeeded

    @property
    def failed(self):
        return self.problem is not None


def tail(path, lines):
    """The last lines of a text file (empty when unreadable)."""
    try:
        with open(path, errors="replace") as stream:
            return "".join(stream.readlines()[-lines:]).rstrip()
    except OSError:
        return ""


def run_command(command, log_dir, timeout):
    """Runs command with its output in log_dir; returns (exit code, wall seconds, max RSS kB or None, timed out).

    The command runs under GNU time (when present) for its peak memory, in its own process group so that a
    timeout kills the command and not only the wrapper.
    """
    memory_path = os.path.join(log_dir, "time.txt")
    measure_memory = os.access(GNU_TIME, os.X_OK)
    if measure_memory:
        command = [GNU_TIME, "-f", "%M", "-o", memory_path] + command
    with open(os.path.join(log_dir, "stdout.txt"), "w") as out, open(os.path.join(log_dir, "stderr.txt"), "w") as err:
        start = time.monotonic()
        process = subprocess.Popen(command, stdout=out, stderr=err, stdin=subprocess.DEVNULL, start_new_session=True)
        timed_out = False
        try:
            code = process.wait(timeout=timeout if timeout and timeout > 0 else None)
        except subprocess.TimeoutExpired:
            timed_out = True
            os.killpg(process.pid, signal.SIGKILL)
            code = process.wait()
        seconds = time.monotonic() - start
    return code, seconds, read_max_rss(memory_path) if measure_memory else None, timed_out


def read_max_rss(path):
    """The %M value (kB) GNU time wrote last in path, None when absent."""
    try:
        with open(path) as stream:
            lines = [line.strip() for line in stream if line.strip()]
        return int(lines[-1]) if lines else None
    except (OSError, ValueError):
        return None


def run_case(binary, case, column, out_root, timeout, agreement=False):
    """Runs the offline command for one case and column (label, method, parameter file or None) and reads its
    metrics (and, with `agreement`, compares its rooms with the case's reference_rooms.png)."""
    label, method, params = column
    run = Run(case, label)
    out_dir = os.path.join(out_root, label, case.env, case.name)
    log_dir = out_dir + ".log"
    shutil.rmtree(out_dir, ignore_errors=True)
    os.makedirs(log_dir, exist_ok=True)
    command = [binary, "--map", case.path("map.yaml"), "--doors", case.path("doors.yaml"), "--method", method,
               "--out", out_dir, "--gt-rooms", case.path("gt_rooms.png")]
    if params:
        command += ["--params", params]
    try:
        code, run.seconds, run.max_rss_kb, timed_out = run_command(command, log_dir, timeout)
    except OSError as error:
        run.problem = "cannot run %s: %s" % (binary, error)
        return run
    if timed_out or code != 0:
        reason = "timed out after %g s" % timeout if timed_out else "exit code %d" % code
        excerpt = tail(os.path.join(log_dir, "stderr.txt"), STDERR_EXCERPT_LINES) or tail(
            os.path.join(log_dir, "stdout.txt"), STDERR_EXCERPT_LINES)
        run.problem = reason + (":\n" + excerpt if excerpt else "")
        return run
    metrics_path = os.path.join(out_dir, "metrics.yaml")
    try:
        with open(metrics_path) as stream:
            metrics = yaml.safe_load(stream)
        run.mean_iou = float(metrics["mean_iou"])
        run.iou_total = float(metrics["iou_total"])
        run.door_ious = [float(room["iou"]) for room in metrics.get("rooms") or []]
    except (OSError, yaml.YAMLError, TypeError, KeyError, ValueError) as error:
        run.mean_iou = run.iou_total = 0.0
        run.problem = "cannot read %s: %s" % (metrics_path, error)
        return run
    if agreement and case.reference_iou is not None:
        try:
            rooms = read_label_image(os.path.join(out_dir, "rooms.png"))
            reference = read_label_image(case.path("reference_rooms.png"))
            if rooms.shape != reference.shape:
                raise ValueError("rooms.png is %dx%d, reference_rooms.png %dx%d" % (
                    rooms.shape[1], rooms.shape[0], reference.shape[1], reference.shape[0]))
            run.agreement = door_ious(rooms, reference, case.doors, both_empty=1.0)
        except ValueError as error:
            run.problem = "cannot compare with the reference: %s" % error
    return run


def run_all(binary, cases, columns, out_root, jobs, timeout, agreement=False):
    """Runs every column (label, method, parameter file or None) on every case in parallel, with a progress bar;
    returns {label: [Run]} in case order."""
    tasks = [(case, column) for column in columns for case in cases]
    results = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {pool.submit(run_case, binary, case, column, out_root, timeout, agreement): (case, column[0])
                   for case, column in tasks}
        with tqdm(total=len(futures), unit="run", desc="cases", file=sys.stderr) as progress:
            for future in concurrent.futures.as_completed(futures):
                case, label = futures[future]
                results[(case.label, label)] = future.result()
                progress.update(1)
    return {label: [results[(case.label, label)] for case in cases] for label, _, _ in columns}


# --------------------------------------------------------------------------------------------------------
# Report


def mean_or_none(values):
    """Mean of the values that are not None, None when there are none."""
    values = [value for value in values if value is not None]
    return float(np.mean(values)) if values else None


def format_score(value, width=8):
    return ("%.4f" % value if value is not None else "-").rjust(width)


def score_columns(indices, cases, methods, runs, width):
    """The mean IoU of each method and of the reference over the cases at `indices`, as columns of `width`."""
    means = [mean_or_none([runs[method][i].mean_iou for i in indices]) for method in methods]
    means.append(mean_or_none([cases[i].reference_iou for i in indices]))
    return "".join(format_score(mean, width) for mean in means)


def print_table(cases, methods, runs):
    """Mean IoU by number of closed doors: one row per number, one column per method plus the reference."""
    width = max(12, *(len(method) + 1 for method in methods))
    header = "doors  cases" + "".join(method.rjust(width) for method in methods) + \
        "reference".rjust(width) + "ref cases".rjust(10)
    print("Mean IoU by number of closed doors")
    print(header)
    print("-" * len(header))
    counts = sorted({case.doors for case in cases} | set(range(1, MAX_DOORS_ROW + 1)))
    for doors in counts:
        indices = [i for i, case in enumerate(cases) if case.doors == doors]
        references = [cases[i].reference_iou for i in indices if cases[i].reference_iou is not None]
        print("%5d  %5d" % (doors, len(indices)) + score_columns(indices, cases, methods, runs, width) +
              "%10d" % len(references))
    print()


def print_environments(cases, methods, runs):
    """Mean IoU per environment: a method that wins on average but collapses on some buildings shows it."""
    environments = sorted({case.env for case in cases}, key=str.lower)
    width = max(10, *(len(method) + 1 for method in methods))
    name_width = max(len("environment"), *(len(env) for env in environments))
    with_parts = any(case.part for case in cases)
    header = "environment".ljust(name_width) + ("  part      " if with_parts else "") + "  cases" + \
        "".join(method.rjust(width) for method in methods) + "reference".rjust(width)
    print("Mean IoU per environment")
    print(header)
    print("-" * len(header))
    for env in environments:
        indices = [i for i, case in enumerate(cases) if case.env == env]
        line = env.ljust(name_width)
        if with_parts:
            line += "  " + cases[indices[0]].part.ljust(10)
        line += "  %5d" % len(indices)
        print(line + score_columns(indices, cases, methods, runs, width))
    print()


def print_overall(cases, methods, runs):
    """Overall mean IoU per method and of the reference, and the agreement with cases.csv."""
    with_reference = [i for i, case in enumerate(cases) if case.reference_iou is not None]
    print("Overall (%d valid cases, %d with a reference prediction)" % (len(cases), len(with_reference)))
    name_width = max(len("reference"), *(len(method) for method in methods))
    for method in methods:
        method_runs = runs[method]
        on_reference = " (%.4f over the %d with a reference)" % (
            np.mean([method_runs[i].mean_iou for i in with_reference]), len(with_reference)) if with_reference else ""
        print("  %s  mean IoU %.4f over %d cases%s, mean IoU_tot %.4f" % (
            method.ljust(name_width), np.mean([run.mean_iou for run in method_runs]), len(method_runs), on_reference,
            np.mean([run.iou_total for run in method_runs])))
    if with_reference:
        reference = mean_or_none(cases[i].reference_iou for i in with_reference)
        print("  %s  mean IoU %s over %d cases" % ("reference".ljust(name_width), format_score(reference, 0),
                                                  len(with_reference)))
    differences = [abs(case.reference_iou - case.csv_reference_iou) for case in cases
                   if case.reference_iou is not None and case.csv_reference_iou is not None]
    if differences:
        print("  reference vs cases.csv reference_iou: max difference %.4f over %d cases" % (
            max(differences), len(differences)))
    for case in cases:
        if case.reference_problem is not None:
            print("  no reference score for %s: %s" % (case.label, case.reference_problem))
    print()


def print_agreement(cases, methods, runs):
    """Room-by-room agreement with reference_rooms.png (--agreement): per case, by number of closed doors and
    overall, each method's mean over the rooms next to its mean IoU against the truth over the same cases."""
    indices = [i for i, case in enumerate(cases) if case.reference_iou is not None]
    print("Agreement with the thesis's implementation: room-by-room IoU with reference_rooms.png (1 when both are")
    print("empty), next to the mean IoU against the truth; %d cases with a reference" % len(indices))
    if not indices:
        print()
        return
    width = max(len("ref IoU"), *(len(method) + 4 for method in methods)) + 2
    label_width = max(len(cases[i].label) for i in indices)
    header = "".join(("%s agr" % method).rjust(width) + ("%s IoU" % method).rjust(width) for method in methods)
    print("%s  doors%s%s" % ("case".ljust(label_width), header, "ref IoU".rjust(width)))
    for i in indices:
        columns = []
        for method in methods:
            run = runs[method][i]
            columns.append(format_score(None if run.agreement is None else np.mean(run.agreement), width))
            columns.append(format_score(None if run.failed else run.mean_iou, width))
        print("%s  %5d%s%s" % (cases[i].label.ljust(label_width), cases[i].doors, "".join(columns),
                               format_score(cases[i].reference_iou, width)))
    print()

    def rooms_of(method, selected):
        return [value for i in selected for value in (runs[method][i].agreement or [])]

    print("By number of closed doors (agreement: mean over the rooms)")
    print("doors  rooms%s%s" % (header, "ref IoU".rjust(width)))
    for doors in sorted({cases[i].doors for i in indices}):
        selected = [i for i in indices if cases[i].doors == doors]
        columns = []
        for method in methods:
            columns.append(format_score(mean_or_none(rooms_of(method, selected)), width))
            columns.append(format_score(mean_or_none(runs[method][i].mean_iou for i in selected), width))
        print("%5d  %5d%s%s" % (doors, doors * len(selected), "".join(columns),
                               format_score(mean_or_none(cases[i].reference_iou for i in selected), width)))
    for method in methods:
        rooms = rooms_of(method, indices)
        if rooms:
            print("  %s: agreement mean %.4f, median %.4f over %d rooms; mean IoU %.4f against the reference's %.4f"
                  % (method, np.mean(rooms), np.median(rooms), len(rooms),
                     np.mean([runs[method][i].mean_iou for i in indices]),
                     np.mean([cases[i].reference_iou for i in indices])))
    print()


def best_of_mean(indices, methods, runs):
    """Mean over the cases at `indices` of the mean over their doors of the best IoU any of `methods` has on the
    door (a failed run, or one without a door's IoU, offers nothing there)."""
    means = []
    for i in indices:
        doors = max(len(runs[method][i].door_ious) for method in methods)
        best = [max((runs[method][i].door_ious[k] for method in methods if k < len(runs[method][i].door_ious)),
                    default=0.0) for k in range(doors)]
        means.append(float(np.mean(best)) if best else 0.0)
    return mean_or_none(means)


def print_best_of(cases, methods, runs):
    """--best-of: per part (and over all cases), each column's mean IoU and the mean IoU of the best column per
    door."""
    parts = sorted({case.part for case in cases if case.part})
    groups = [(part, [i for i, case in enumerate(cases) if case.part == part]) for part in parts]
    groups.append(("all", list(range(len(cases)))))
    width = max(10, *(len(method) + 1 for method in methods))
    header = "part".ljust(12) + "  cases" + "".join(method.rjust(width) for method in methods) + "best of".rjust(width)
    print("Best column per door: the mean IoU if every door took the room of the column best on it")
    print(header)
    print("-" * len(header))
    for name, indices in groups:
        means = [mean_or_none([runs[method][i].mean_iou for i in indices]) for method in methods]
        print(name.ljust(12) + "  %5d" % len(indices) + "".join(format_score(mean, width) for mean in means) +
              format_score(best_of_mean(indices, methods, runs), width))
    print()


def print_resources(methods, runs):
    """Median and p95 wall seconds per case, and peak memory, per method."""
    print("Time per case (wall time of the whole command, successful runs) and peak memory (max RSS, /usr/bin/time)")
    name_width = max(len("method"), *(len(method) for method in methods))
    print("  %s  %6s  %9s  %9s  %12s" % ("method".ljust(name_width), "runs", "median s", "p95 s", "peak RSS MB"))
    for method in methods:
        seconds = [run.seconds for run in runs[method] if not run.failed and run.seconds is not None]
        rss = [run.max_rss_kb for run in runs[method] if not run.failed and run.max_rss_kb is not None]
        median = "%9.3f" % np.median(seconds) if seconds else "%9s" % "-"
        p95 = "%9.3f" % np.percentile(seconds, 95) if seconds else "%9s" % "-"
        peak = "%12.1f" % (max(rss) / 1024.0) if rss else "%12s" % "-"
        print("  %s  %6d  %s  %s  %s" % (method.ljust(name_width), len(seconds), median, p95, peak))
    if not os.access(GNU_TIME, os.X_OK):
        print("  (peak memory not measured: %s is missing)" % GNU_TIME)
    print()


def print_failures(methods, runs):
    """Every failed run with its stderr excerpt; returns the number of failures."""
    failures = [run for method in methods for run in runs[method] if run.failed]
    if failures:
        print("%d failed run(s), counted with IoU 0:" % len(failures))
        for run in failures[:MAX_FAILURES_LISTED]:
            print("  %s %s: %s" % (run.method, run.case.label, run.problem.replace("\n", "\n      ")))
        if len(failures) > MAX_FAILURES_LISTED:
            print("  ... and %d more (the CSV's status column lists them all)" % (len(failures) - MAX_FAILURES_LISTED))
        print()
    return len(failures)


def write_csv(path, cases, methods, runs):
    """Per-case rows: env, case, doors, method, mean_iou, iou_total, seconds, reference_iou, status, max_rss_mb."""
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["env", "case", "doors", "method", "mean_iou", "iou_total", "seconds", "reference_iou",
                         "status", "max_rss_mb"])
        for method in methods:
            for case, run in zip(cases, runs[method]):
                writer.writerow([case.env, case.name, case.doors, method, "%.6f" % run.mean_iou,
                                 "%.6f" % run.iou_total, "" if run.seconds is None else "%.4f" % run.seconds,
                                 "" if case.reference_iou is None else "%.6f" % case.reference_iou,
                                 "failed" if run.failed else "ok",
                                 "" if run.max_rss_kb is None else "%.1f" % (run.max_rss_kb / 1024.0)])


def write_plot(path, cases, methods, runs):
    """Mean IoU vs number of closed doors per method and for the reference."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    counts = sorted({case.doors for case in cases})
    figure, axes = plt.subplots(figsize=(8, 4.5))
    series = [(method, [runs[method][i].mean_iou for i in range(len(cases))]) for method in methods]
    series.append(("reference", [case.reference_iou for case in cases]))
    for name, scores in series:
        xs, ys = [], []
        for doors in counts:
            value = mean_or_none(score for case, score in zip(cases, scores) if case.doors == doors)
            if value is not None:
                xs.append(doors)
                ys.append(value)
        axes.plot(xs, ys, marker="o", linestyle="--" if name == "reference" else "-", label=name)
    axes.set_xlabel("closed doors")
    axes.set_ylabel("mean IoU")
    axes.set_ylim(0, 1)
    axes.set_xticks(counts)
    axes.grid(True, alpha=0.3)
    axes.legend()
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    plt.close(figure)


# --------------------------------------------------------------------------------------------------------


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Benchmark room-prediction methods on a closed-door benchmark folder.")
    parser.add_argument("bench_dir", metavar="BENCH_DIR", help="benchmark folder with cases.csv")
    parser.add_argument("--part", help="only the cases whose cases.csv `part` is this (e.g. validation)")
    parser.add_argument("--method", action="append", default=[], help="a prediction method (repeatable)")
    parser.add_argument("--methods", default="", help="comma-separated methods, printed side by side")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="parallel runs (default: cores)")
    parser.add_argument("--binary", help="path of predict_rooms_offline (default: look in the workspace)")
    parser.add_argument("--keep", metavar="DIR", help="keep the outputs of every run in DIR")
    parser.add_argument("--params", metavar="FILE.yaml",
                        help="parameter overrides passed to every run of the methods (a --variant has its own)")
    parser.add_argument("--csv", metavar="FILE", help="write the per-case rows to FILE")
    parser.add_argument("--plot", metavar="FILE.png", help="plot mean IoU vs closed doors to FILE.png")
    parser.add_argument("--agreement", action="store_true",
                        help="compare each method's rooms with reference_rooms.png, room by room")
    parser.add_argument("--turn", type=float, default=0.0, metavar="DEGREES",
                        help="turn every case's map, true rooms and doors by this many degrees counter-clockwise "
                             "first (as a SLAM map off the building's axes); no reference scores then")
    parser.add_argument("--variant", nargs=3, action="append", default=[], metavar=("LABEL", "METHOD", "PARAMS.yaml"),
                        help="one more column LABEL: METHOD with the parameter overrides of PARAMS.yaml (repeatable)")
    parser.add_argument("--best-of", action="store_true",
                        help="also print, per part, the mean IoU of the best column on each door")
    parser.add_argument("--timeout", type=float, default=600.0,
                        help="seconds before a run is killed and counted as failed (default 600, 0 = none)")
    args = parser.parse_args(argv)
    methods = []
    for name in args.method + args.methods.split(","):
        name = name.strip()
        if name and name not in methods:
            methods.append(name)
    if not methods and not args.variant:
        parser.error("give at least one method with --method NAME, --methods A,B or --variant")
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    if args.params and not os.path.isfile(args.params):
        parser.error("--params %s does not exist" % args.params)
    params = os.path.abspath(args.params) if args.params else None
    args.columns = [(method, method, params) for method in methods]
    for label, method, variant_params in args.variant:
        if not label.strip() or os.sep in label or label in [column[0] for column in args.columns]:
            parser.error("--variant %r: give each variant a label of its own that names no folder" % label)
        if not os.path.isfile(variant_params):
            parser.error("--variant %s: %s does not exist" % (label, variant_params))
        args.columns.append((label, method, os.path.abspath(variant_params)))
    if args.best_of and len(args.columns) < 2:
        parser.error("--best-of compares columns: give at least two methods or variants")
    if not np.isfinite(args.turn):
        parser.error("--turn must be a finite number of degrees")
    if args.turn and args.agreement:
        parser.error("--agreement compares with the reference rooms of the straight maps: not with --turn")
    args.method_list = [column[0] for column in args.columns]
    return args


def main(argv=None):
    args = parse_arguments(argv)
    try:
        cases = load_cases(args.bench_dir, args.part)
        binary = find_binary(args.binary)
        available = known_methods(binary)
        unknown = sorted({method for _, method, _ in args.columns if available is not None and method not in available})
        if unknown:
            raise BenchmarkError("unknown method(s) %s; %s knows: %s" % (
                ", ".join(unknown), BINARY_NAME, ", ".join(available)))
    except BenchmarkError as error:
        print("benchmark_closed_doors.py: error: %s" % error, file=sys.stderr)
        return 2

    if args.keep:
        os.makedirs(args.keep, exist_ok=True)
        out_root = args.keep
    else:
        out_root = tempfile.mkdtemp(prefix="benchmark_closed_doors_")
    if args.turn:
        cases = [turned_case(case, args.turn, os.path.join(out_root, "turned")) for case in cases]
    else:
        for case in cases:
            score_reference(case)
    print("%s: %d valid cases%s, methods %s, %d jobs, binary %s" % (
        args.bench_dir, len(cases), ", turned by %g degrees" % args.turn if args.turn else "",
        ", ".join(args.method_list), args.jobs, binary))
    sys.stdout.flush()
    try:
        runs = run_all(binary, cases, args.columns, out_root, args.jobs, args.timeout, args.agreement)
    finally:
        if not args.keep:
            shutil.rmtree(out_root, ignore_errors=True)

    print()
    print_table(cases, args.method_list, runs)
    print_environments(cases, args.method_list, runs)
    print_overall(cases, args.method_list, runs)
    if args.agreement:
        print_agreement(cases, args.method_list, runs)
    if args.best_of:
        print_best_of(cases, args.method_list, runs)
    print_resources(args.method_list, runs)
    failures = print_failures(args.method_list, runs)
    if args.csv:
        write_csv(args.csv, cases, args.method_list, runs)
        print("per-case rows written to %s" % args.csv)
    if args.plot:
        write_plot(args.plot, cases, args.method_list, runs)
        print("plot written to %s" % args.plot)
    if args.keep:
        print("run outputs kept in %s" % args.keep)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
