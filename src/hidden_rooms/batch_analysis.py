"""The thesis's batch analysis (docs/method.md#batch-analysis), driven from Python, computed by the C++ tool
`batch_cases`.

Per environment and batch: a random order of the closable doors (seeded by --seed, the environment's name and
the batch number, so that every machine and every re-run draws the same doors), cut to --max-closed doors; case
k closes the first k doors. `batch_cases` renders each case (rooms erased, doors painted as walls), runs every
method and scores it; this module schedules the batches (local threads or a Dask cluster), appends one row per
case to DIR/results.csv as soon as it is done, and resumes from the rows already there.

`scripts/batch_analysis` is the command line (see `main`).
"""
import concurrent.futures
import csv
import fcntl
import io
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time

from hidden_rooms.package_tools import ArgumentParser, ToolError, find_binary, tool_error

TOOL_NAME = "batch_cases"
RESULTS_NAME = "results.csv"
SETTINGS_NAME = "batch_settings.json"
LOCK_NAME = ".batch_analysis.lock"
TASK_FOLDER_PREFIX = "batch_task_"
ALL_METHODS = ["default", "thesis", "unstructured", "structured", "skewnormal"]
STDERR_EXCERPT_CHARS = 2000

# Size classes by number of closable doors (docs/method.md#batch-analysis, the thesis's classes).
SMALL_MAX_CLOSABLE = 9     # small: fewer than 10 closable doors
MEDIUM_MAX_CLOSABLE = 15   # medium: 10 to 15; large: 16 or more
SIZE_CLASSES = ["small", "medium", "large"]


class BatchError(ToolError):
    """Unusable arguments or input (exit code 2)."""


# The batch_cases processes running in this process (stopped on Ctrl-C).
_RUNNING = set()
_RUNNING_LOCK = threading.Lock()
_STOPPING = threading.Event()


def stop_running_tools():
    """Stops every batch_cases process of this process; tasks started afterwards return at once."""
    _STOPPING.set()
    with _RUNNING_LOCK:
        for process in list(_RUNNING):
            if process.poll() is None:
                process.kill()


def size_class(closable_doors):
    """The thesis's size class of an environment from its number of closable doors."""
    if closable_doors <= SMALL_MAX_CLOSABLE:
        return "small"
    if closable_doors <= MEDIUM_MAX_CLOSABLE:
        return "medium"
    return "large"


def result_columns(methods):
    """The header of results.csv for these methods."""
    return (["environment", "size_class", "batch", "closed_doors"] +
            ["iou_%s" % method for method in methods] +
            ["iou_tot_%s" % method for method in methods] +
            ["hidden_percent", "closed_door_ids"] +
            ["seconds_%s" % method for method in methods] +
            ["case_seconds", "failed_methods"])


def methods_of(columns):
    """The methods of a results.csv header (its iou_<method> columns, in order)."""
    return [name[len("iou_"):] for name in columns if name.startswith("iou_") and not name.startswith("iou_tot_")]


# --------------------------------------------------------------------------------------------------------
# The C++ tool


class Environment:
    """An environment to analyse: its file, text and closable doors (from `batch_cases --info`)."""

    def __init__(self, path, binary):
        self.path = os.path.abspath(path)
        if not os.path.isfile(self.path):
            raise BatchError("%s: no such environment file" % path)
        with open(self.path, "rb") as stream:
            self.xml = stream.read()
        result = subprocess.run([binary, self.path, "--info"], capture_output=True, text=True,
                                stdin=subprocess.DEVNULL)
        if result.returncode != 0:
            raise BatchError(tool_error(result, "%s --info" % TOOL_NAME))
        info = json.loads(result.stdout.strip().splitlines()[-1])
        self.closable = [int(door) for door in info["closable"]]
        self.spaces = int(info["spaces"])
        self.doors = int(info["doors"])
        self.floor_area = float(info["floor_area"])
        if not self.closable:
            raise BatchError("%s: no closable door (a door whose room has exactly that one door)" % path)
        self.size_class = size_class(len(self.closable))
        self.name = os.path.splitext(os.path.basename(self.path))[0]


def door_sequence(seed, environment_name, batch, closable, max_closed):
    """The doors closed in a batch, in closing order: a seeded shuffle of the closable doors, cut to max_closed.

    The shuffle does not depend on max_closed, so that raising it extends the batches already run."""
    order = sorted(closable)
    random.Random("%s/%s/%d" % (seed, environment_name, batch)).shuffle(order)
    return order[:max_closed]


class Task:
    """The pending cases of one batch: everything a worker needs (the environment's text, not its path)."""

    def __init__(self, environment, batch, sequence, cases, methods, settings):
        self.environment_name = environment.name
        self.size_class = environment.size_class
        self.xml = environment.xml
        self.batch = batch
        self.sequence = sequence
        self.cases = cases
        self.methods = methods
        self.params = settings.get("params_text")
        self.tool_options = settings.get("tool_options", [])
        self.binary = settings.get("binary")
        self.keep_dir = settings.get("keep_dir")

    def key(self, closed):
        return (self.environment_name, self.batch, closed)


def to_row(task, case):
    """A results.csv row (dict of text) from one JSON line of batch_cases."""
    row = {"environment": task.environment_name, "size_class": task.size_class, "batch": str(task.batch),
           "closed_doors": str(case["closed_doors"]), "hidden_percent": "%.3f" % case["hidden_percent"],
           "closed_door_ids": " ".join(str(door) for door in case["door_ids"]),
           "case_seconds": "%.4f" % case["case_seconds"]}
    failed = []
    for method in task.methods:
        outcome = case["methods"][method]
        row["iou_%s" % method] = "%.4f" % (outcome["mean_iou"] or 0.0)
        row["iou_tot_%s" % method] = "%.4f" % (outcome["iou_total"] or 0.0)
        row["seconds_%s" % method] = "%.4f" % outcome["seconds"]
        if outcome.get("problem"):
            failed.append(method)
    row["failed_methods"] = " ".join(failed)
    return row


def remove_stale_task_folders():
    """Removes the task folders (TMP/batch_task_PID_*) of processes that no longer run: a SIGKILL leaves them."""
    pattern = re.compile(r"^%s(\d+)_" % TASK_FOLDER_PREFIX)
    for name in os.listdir(tempfile.gettempdir()):
        match = pattern.match(name)
        if not match:
            continue
        try:
            os.kill(int(match.group(1)), 0)
        except ProcessLookupError:
            shutil.rmtree(os.path.join(tempfile.gettempdir(), name), ignore_errors=True)
        except (PermissionError, OverflowError):
            pass  # another user's process, or no process id


def run_task(task, on_row=None):
    """Runs batch_cases on the task's cases; returns the rows (also passed to on_row one by one as they come).

    Runs wherever it is called: in a local thread, or on a Dask worker (which needs only the package)."""
    binary = find_binary(TOOL_NAME, task.binary)
    rows = []
    with tempfile.TemporaryDirectory(prefix="%s%d_" % (TASK_FOLDER_PREFIX, os.getpid())) as folder:
        env_path = os.path.join(folder, task.environment_name.replace("/", "_") + ".xml")
        with open(env_path, "wb") as stream:
            stream.write(task.xml)
        command = [binary, env_path, "--sequence", ",".join(map(str, task.sequence)),
                   "--cases", ",".join(map(str, task.cases)), "--methods", ",".join(task.methods)]
        if task.params is not None:
            params_path = os.path.join(folder, "params.yaml")
            with open(params_path, "w") as stream:
                stream.write(task.params)
            command += ["--params", params_path]
        if task.keep_dir:
            command += ["--write-cases", os.path.join(task.keep_dir, task.environment_name, "batch_%d" % task.batch)]
        command += task.tool_options
        stderr_path = os.path.join(folder, "stderr.txt")
        with open(stderr_path, "w") as stderr:
            if _STOPPING.is_set():
                raise RuntimeError("stopped")
            process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=stderr, stdin=subprocess.DEVNULL,
                                       text=True)
            with _RUNNING_LOCK:
                _RUNNING.add(process)
            try:
                for line in process.stdout:
                    if not line.strip():
                        continue
                    row = to_row(task, json.loads(line))
                    rows.append(row)
                    if on_row is not None:
                        on_row(row)
            finally:
                process.stdout.close()
                code = process.wait()
                with _RUNNING_LOCK:
                    _RUNNING.discard(process)
        if code != 0:
            with open(stderr_path, errors="replace") as stream:
                message = stream.read()[-STDERR_EXCERPT_CHARS:].strip()
            raise RuntimeError("%s batch %d: %s exit code %d: %s" % (
                task.environment_name, task.batch, TOOL_NAME, code, message))
    return rows


# --------------------------------------------------------------------------------------------------------
# results.csv


class ResultsFile:
    """DIR/results.csv: read the rows already there (dropping a line cut by a kill), append rows one by one."""

    def __init__(self, path, columns):
        self.path = path
        self.columns = columns
        self.done = {}
        self.lock = threading.Lock()
        if os.path.isfile(path) and os.path.getsize(path) > 0:
            self._repair()
            with open(path, newline="") as stream:
                reader = csv.DictReader(stream)
                if reader.fieldnames != columns:
                    raise BatchError("%s has the columns %s, this run writes %s: use the same --methods or "
                                     "another --out" % (path, ",".join(reader.fieldnames or []), ",".join(columns)))
                for row in reader:
                    self.done[(row["environment"], int(row["batch"]), int(row["closed_doors"]))] = row
        else:
            with open(path, "w", newline="") as stream:
                csv.writer(stream).writerow(columns)

    def _repair(self):
        """Cuts a last line without its newline (the run was killed while writing it)."""
        with open(self.path, "rb+") as stream:
            data = stream.read()
            if data.endswith(b"\n"):
                return
            stream.truncate(data.rfind(b"\n") + 1)

    def append(self, row):
        """Writes one row in one write() of an O_APPEND file, flushed to disk."""
        buffer = io.StringIO()
        csv.DictWriter(buffer, fieldnames=self.columns, lineterminator="\n").writerow(row)
        data = buffer.getvalue().encode()
        with self.lock:
            key = (row["environment"], int(row["batch"]), int(row["closed_doors"]))
            if key in self.done:
                return False
            descriptor = os.open(self.path, os.O_WRONLY | os.O_APPEND)
            try:
                os.write(descriptor, data)
                os.fsync(descriptor)
            finally:
                os.close(descriptor)
            self.done[key] = row
            return True


def check_settings(out_dir, settings):
    """Stores the settings that change the rows (seed, methods, parameters, rendering) in DIR, and refuses to
    resume a folder written with other ones."""
    path = os.path.join(out_dir, SETTINGS_NAME)
    fixed = {key: settings[key] for key in ("seed", "methods", "params_text", "tool_options", "map")}
    if os.path.isfile(path):
        with open(path) as stream:
            stored = json.load(stream)
        different = sorted(key for key in fixed if stored.get(key) != fixed[key])
        if different:
            raise BatchError("%s was written with other settings (%s): use the same ones to resume, or another "
                             "--out" % (out_dir, ", ".join(different)))
    else:
        with open(path, "w") as stream:
            json.dump(fixed, stream, indent=2)


# --------------------------------------------------------------------------------------------------------
# Scheduling


def run_local(tasks, jobs, on_row):
    """Runs the tasks on local threads (each runs one batch_cases process); returns the failures."""
    failures = []
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=jobs)
    futures = {}
    try:
        futures = {pool.submit(run_task, task, on_row): task for task in tasks}
        for future in concurrent.futures.as_completed(futures):
            try:
                future.result()
            except Exception as error:  # noqa: B902 - reported, the other batches go on
                failures.append(str(error))
    except KeyboardInterrupt:
        for future in futures:
            future.cancel()
        stop_running_tools()
        raise
    finally:
        pool.shutdown(wait=True)
    return failures


def run_dask(tasks, scheduler, on_row):
    """Sends the tasks to a Dask distributed scheduler; appends each batch's rows when it comes back."""
    try:
        from dask.distributed import Client, as_completed
    except ImportError as error:
        raise BatchError("--scheduler needs Dask distributed (Debian: python3-distributed): %s" % error)
    failures = []
    try:
        client = Client(scheduler, timeout=30)
    except (OSError, TimeoutError) as error:
        raise BatchError("cannot connect to the Dask scheduler %s: %s" % (scheduler, error))
    try:
        futures = [client.submit(run_task, task, pure=False, key="batch-%s-%d-%d" % (
            task.environment_name, task.batch, time.monotonic_ns())) for task in tasks]
        for future in as_completed(futures):
            try:
                for row in future.result():
                    on_row(row)
            except Exception as error:  # noqa: B902
                failures.append(str(error))
    finally:
        client.close()
    return failures


# --------------------------------------------------------------------------------------------------------
# Command line


def parse_arguments(argv):
    parser = ArgumentParser(
        prog="batch_analysis",
        description="The thesis's batch analysis (docs/method.md#batch-analysis): per environment and batch, close "
                    "the closable doors one at a time at random, cumulatively, erase the rooms behind them, run every method "
                    "and score it against the true rooms. Rows go to OUT/results.csv as they are done; re-running "
                    "the same command resumes.")
    parser.add_argument("--env", nargs="+", required=True, metavar="ENV.xml", help="environment XML file(s)")
    parser.add_argument("--map", help="complete map (map_server yaml) to use instead of the rendering "
                                      "(one --env only; needs --doors-in-map)")
    parser.add_argument("--doors-in-map", help="with --map: doors.yaml with every door's position in the map")
    parser.add_argument("--batches", type=int, default=15, help="batches per environment (default 15)")
    parser.add_argument("--max-closed", type=int, default=15,
                        help="doors closed at most per batch (default 15; fewer when the environment has fewer "
                             "closable doors)")
    parser.add_argument("--methods", default=",".join(ALL_METHODS),
                        help="comma-separated methods (default: %(default)s)")
    parser.add_argument("--out", required=True, help="output folder (results.csv)")
    parser.add_argument("--seed", default="0", help="seed of the door orders (default 0)")
    parser.add_argument("--params", help="parameter overrides (flat YAML of name: number)")
    parser.add_argument("--resolution", type=float, default=0.05, help="metres per cell (default 0.05)")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1,
                        help="parallel batches on this machine (default: all cores)")
    parser.add_argument("--scheduler", help="Dask distributed scheduler address, e.g. tcp://HOST:8786 "
                                            "(instead of local processes)")
    parser.add_argument("--keep-cases", action="store_true",
                        help="also write each case's input (map, doors.yaml, true_rooms.png) under OUT/cases/")
    parser.add_argument("--binary", help="path of batch_cases (default: found in the workspace)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)
    if args.batches < 1:
        parser.error("--batches must be at least 1")
    if args.max_closed < 1:
        parser.error("--max-closed must be at least 1")
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    if not args.resolution > 0:
        parser.error("--resolution must be positive")
    if bool(args.map) != bool(args.doors_in_map):
        parser.error("--map and --doors-in-map go together")
    if args.map and len(args.env) != 1:
        parser.error("--map works with one --env")
    args.method_list = [method.strip() for method in args.methods.split(",") if method.strip()]
    if not args.method_list:
        parser.error("--methods names no method")
    if len(set(args.method_list)) != len(args.method_list):
        parser.error("--methods names a method twice")
    return args


def known_methods(binary):
    """Method names listed by `batch_cases --help`."""
    result = subprocess.run([binary, "--help"], capture_output=True, text=True, stdin=subprocess.DEVNULL)
    for line in result.stdout.splitlines():
        if line.startswith("Methods:"):
            return [name.strip() for name in line.split(":", 1)[1].split(",") if name.strip()]
    return None


def load_environments(paths, binary):
    environments = [Environment(path, binary) for path in paths]
    names = [environment.name for environment in environments]
    for environment in environments:  # same file name in two folders: name them folder/name
        if names.count(environment.name) > 1:
            environment.name = "%s/%s" % (os.path.basename(os.path.dirname(environment.path)), environment.name)
    names = [environment.name for environment in environments]
    if len(set(names)) != len(names):
        raise BatchError("an environment is given twice")
    return environments


def summarize(rows, methods, out):
    """Mean IoU per method over the rows, printed."""
    if not rows:
        return
    out.write("mean IoU over %d cases:" % len(rows))
    for method in methods:
        values = [float(row["iou_%s" % method]) for row in rows]
        out.write("  %s %.3f" % (method, sum(values) / len(values)))
    out.write("\n")


def main(argv=None):
    args = parse_arguments(sys.argv[1:] if argv is None else argv)
    remove_stale_task_folders()
    try:
        binary = find_binary(TOOL_NAME, args.binary)
        available = known_methods(binary)
        unknown = [method for method in args.method_list if available is not None and method not in available]
        if unknown:
            raise BatchError("unknown method(s) %s (known: %s)" % (", ".join(unknown), ", ".join(available)))
        params_text = None
        if args.params:
            if not os.path.isfile(args.params):
                raise BatchError("%s: no such parameters file" % args.params)
            with open(args.params) as stream:
                params_text = stream.read()
        for path in [args.map, args.doors_in_map]:
            if path and not os.path.isfile(path):
                raise BatchError("%s: no such file" % path)
        environments = load_environments(args.env, binary)
        if args.params:  # checked by the tool itself (names, values) before the settings record it
            check = subprocess.run([binary, environments[0].path, "--info", "--methods", ",".join(args.method_list),
                                    "--params", os.path.abspath(args.params)],
                                   capture_output=True, text=True, stdin=subprocess.DEVNULL)
            if check.returncode != 0:
                raise BatchError(tool_error(check, "%s --params" % TOOL_NAME).replace("%s: error: " % TOOL_NAME, ""))
        tool_options = ["--resolution", repr(args.resolution)]
        if args.map:
            tool_options += ["--map", os.path.abspath(args.map), "--doors-in-map", os.path.abspath(args.doors_in_map)]
        os.makedirs(args.out, exist_ok=True)
        lock = open(os.path.join(args.out, LOCK_NAME), "w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise BatchError("another batch_analysis is writing %s" % args.out)
        settings = {"seed": str(args.seed), "methods": args.method_list, "params_text": params_text,
                    "tool_options": tool_options, "map": bool(args.map),
                    "binary": os.path.abspath(args.binary) if args.binary else None,
                    "keep_dir": os.path.abspath(os.path.join(args.out, "cases")) if args.keep_cases else None}
        check_settings(args.out, settings)
        results = ResultsFile(os.path.join(args.out, RESULTS_NAME), result_columns(args.method_list))
    except ToolError as error:
        print("batch_analysis: error: %s" % error, file=sys.stderr)
        return 2

    tasks = []
    total_cases = 0
    for environment in environments:
        for batch in range(1, args.batches + 1):
            sequence = door_sequence(args.seed, environment.name, batch, environment.closable, args.max_closed)
            total_cases += len(sequence)
            pending = [k for k in range(1, len(sequence) + 1) if (environment.name, batch, k) not in results.done]
            if pending:
                tasks.append(Task(environment, batch, sequence, pending, args.method_list, settings))
    # Largest environments first, so that no long batch is left alone at the end.
    size_rank = {name: rank for rank, name in enumerate(reversed(SIZE_CLASSES))}
    tasks.sort(key=lambda task: (size_rank[task.size_class], -len(task.cases)))
    pending_cases = sum(len(task.cases) for task in tasks)
    where = args.scheduler or "%d local jobs" % args.jobs
    print("batch_analysis: %d environments (%s), %d batches, up to %d closed doors, methods %s: %d cases, "
          "%d already in %s, %d to run on %s" % (
              len(environments), ", ".join("%s %s" % (sum(e.size_class == c for e in environments), c)
                                           for c in SIZE_CLASSES), args.batches, args.max_closed,
              ",".join(args.method_list), total_cases, total_cases - pending_cases, results.path, pending_cases,
              where), flush=True)

    from tqdm import tqdm
    start = time.monotonic()
    new_rows = []
    batches_left = {(task.environment_name, task.batch): len(task.cases) for task in tasks}
    progress = tqdm(total=pending_cases, unit="case", desc="batch analysis", file=sys.stderr,
                    disable=args.no_progress, dynamic_ncols=True)
    progress.set_postfix(batches="0/%d" % len(tasks))
    progress_lock = threading.Lock()

    def on_row(row):
        if results.append(row):
            with progress_lock:
                new_rows.append(row)
                key = (row["environment"], int(row["batch"]))
                batches_left[key] -= 1
                progress.update(1)
                progress.set_postfix(batches="%d/%d" % (sum(1 for left in batches_left.values() if left == 0),
                                                        len(tasks)), refresh=False)

    try:
        if args.scheduler:
            failures = run_dask(tasks, args.scheduler, on_row)
        else:
            failures = run_local(tasks, args.jobs, on_row)
    except ToolError as error:
        progress.close()
        print("batch_analysis: error: %s" % error, file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        progress.close()
        print("batch_analysis: interrupted; %d new rows kept in %s, re-run the same command to resume" % (
            len(new_rows), results.path), file=sys.stderr)
        return 130
    progress.close()
    seconds = time.monotonic() - start
    print("batch_analysis: %d new rows (%d predictions of %d methods) in %.1f s -> %s" % (
        len(new_rows), len(new_rows) * len(args.method_list), len(args.method_list), seconds, results.path))
    summarize(list(results.done.values()), args.method_list, sys.stdout)
    failed_methods = sum(1 for row in new_rows if row["failed_methods"])
    if failed_methods:
        print("batch_analysis: %d cases with a failed method (IoU 0, column failed_methods)" % failed_methods)
    if failures:
        print("batch_analysis: %d batches failed (their missing rows are retried by re-running):" % len(failures),
              file=sys.stderr)
        for failure in failures[:10]:
            print("  " + failure, file=sys.stderr)
        return 1
    return 0
