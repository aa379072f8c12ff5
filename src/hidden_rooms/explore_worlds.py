"""The thesis's exploration script (docs/method.md#exploration-runs, thesis §5.1.5): explore simulated worlds with some
doors closed.

Per world, in its own ROS master on a free port (so several worlds run side by side): exploration_run.launch
(simulator, mapper, explorer, pose_logger, optionally a bag recorder). Every --timeout seconds of simulated time
the map is saved (DIR/WORLD/maps/map_NNN); the run stops when the explorer reports done, when --patience saved
maps in a row each grew by less than --growth over the one before, or at --max-time. Then the final map, the
closed doors translated into the map frame (translate_doors, docs/method.md#closed-doors-in-the-map), the run's scores
against its world and, with --method, the predicted rooms and their IoU are written. DIR/summary.csv has one row per world.

Progress: while a world runs, its worker writes DIR/WORLD/progress.json (phase, simulated time, free area of the
last saved map, goals so far from the explorer's exploration_status, saved maps) about once a second; the main
process shows it as one tqdm bar per running world on stderr (total: --max-time simulated seconds), when stderr is a
terminal and --no-progress is not given.

A re-run keeps the worlds already finished with the same settings (DIR/WORLD/result.json, written atomically)
and runs the others again. Every child process gets SIGTERM when its parent dies, so a run killed even by SIGKILL
leaves no master, simulator or mapper behind.

`scripts/explore_worlds` is the command line (see `main`); each world runs in a worker process
(`--worker`) whose ROS_MASTER_URI names its own master.
"""
import argparse
import concurrent.futures
import csv
import ctypes
import glob
import json
import os
import queue
import random
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import yaml

from hidden_rooms import batch_analysis
from hidden_rooms.package_tools import ArgumentParser, ToolError, find_binary, tool_error

SUMMARY_NAME = "summary.csv"
RESULT_NAME = "result.json"
PROGRESS_NAME = "progress.json"
SUMMARY_COLUMNS = ["world", "status", "closed_doors", "sim_time_s", "wall_time_s", "path_length_m", "coverage",
                   "coverage_all_free", "free_iou", "worst_door_error_m", "mean_iou", "message"]
MASTER_START_TIMEOUT = 60.0   # wall seconds for roslaunch's master and the simulator's clock
PR_SET_PDEATHSIG = 1          # prctl option (linux/prctl.h)
STALL_TIMEOUT = 60.0          # wall seconds without simulated time advancing: the run is stuck
SHUTDOWN_TIMEOUT = 20.0       # wall seconds for roslaunch to stop after SIGINT
WALL_CLOCK_EPOCH = 1e8         # seconds: no simulated run gets this far; wall-clock time (since 1970) is beyond
PROGRESS_INTERVAL = 1.0       # wall seconds between two writes of progress.json (worker) and two bar updates
LOCKSTEP_CHECK = 1.0          # simulated seconds between the stop rules' checks in lockstep (--realtime-factor 0)
POSE_LOG_NAMES = ("poses_map.log", "poses_truth.log")
POSE_PERIOD = 0.1             # simulated seconds between logged poses (the pose_logger's ~period)
POSE_LOG_TIMEOUT = 10.0       # wall seconds the pose logs get, at the lockstep's last hold, to reach its time


def die_with_parent():
    """preexec_fn of the children: SIGTERM when the process that started them dies (even by SIGKILL), so that a
    killed run leaves no simulator, mapper or master behind."""
    ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


def write_json_atomically(path, value):
    with open(path + ".partial", "w") as partial:
        json.dump(value, partial, indent=1)
    os.replace(path + ".partial", path)


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def world_files(paths):
    """Environment XMLs named by `paths` (files, or folders whose *.xml are taken), in order, without repeats."""
    files = []
    for path in paths:
        if os.path.isdir(path):
            found = sorted(glob.glob(os.path.join(path, "*.xml")))
            if not found:
                raise ToolError("%s: no environment XML (*.xml) in this folder" % path)
            files.extend(found)
        elif os.path.isfile(path):
            files.append(path)
        else:
            raise ToolError("%s: no such file or folder" % path)
    unique = []
    for path in (os.path.realpath(f) for f in files):
        if path not in unique:
            unique.append(path)
    return unique


def world_name(path):
    return os.path.splitext(os.path.basename(path))[0]


def closed_doors_of(spec, world, seed):
    """The simulator's closed-doors text for `world`: `spec` itself, or for 'random:N' N of the world's closable
    doors drawn with `seed` and the world's name (the same doors on every machine and re-run)."""
    if not spec.startswith("random:"):
        return spec
    count = int(spec[len("random:"):])  # checked by parse_arguments
    closable = batch_analysis.Environment(world, find_binary(batch_analysis.TOOL_NAME)).closable
    chosen = random.Random("%d/%s" % (seed, world_name(world))).sample(closable, min(count, len(closable)))
    return ",".join(str(door) for door in sorted(chosen))


# --------------------------------------------------------------------------------------------------------
# Progress (progress.json of a running world, shown as a bar)


def write_progress(out_dir, phase, sim_time=0.0, free_area=None, goals=None, maps_saved=0, stop=None):
    """out_dir/progress.json: the phase ('starting', 'exploring', 'finishing'), simulated seconds, mapped free area
    (m²), goals so far, saved maps and, once finishing, the stop reason. Best effort: a failed write is skipped."""
    try:
        write_json_atomically(os.path.join(out_dir, PROGRESS_NAME), {
            "phase": phase, "sim_time": round(sim_time, 1),
            "free_area_m2": None if free_area is None else round(free_area, 2), "goals": goals,
            "maps_saved": maps_saved, "stop": stop})
    except OSError:
        pass


def read_progress(out_dir):
    """The progress.json of a running world, or None (not written yet, or unreadable)."""
    try:
        with open(os.path.join(out_dir, PROGRESS_NAME)) as progress_file:
            return json.load(progress_file)
    except (OSError, ValueError):
        return None


def status_text(progress, floor_area=None):
    """The bar's status of a world from its progress (read_progress): the phase unless exploring, the mapped free
    area (and its share of `floor_area`, m², when known: closed rooms count in it, so a finished run stays below
    100 %), the goals and the saved maps."""
    if not progress or progress.get("phase") == "starting":
        return "starting ROS"
    parts = []
    if progress.get("phase") != "exploring":
        stop = progress.get("stop")
        parts.append("%s (%s)" % (progress["phase"], stop) if stop else progress["phase"])
    free = progress.get("free_area_m2")
    if free is not None:
        mapped = "mapped %.0f m²" % free
        if floor_area:
            mapped += " (%.0f %% of the floor)" % (100.0 * free / floor_area)
        parts.append(mapped)
    goals = progress.get("goals")
    if goals is not None:
        parts.append("%d goal%s" % (goals, "" if goals == 1 else "s"))
    maps = progress.get("maps_saved") or 0
    parts.append("%d map%s saved" % (maps, "" if maps == 1 else "s"))
    return ", ".join(parts)


def floor_area_of(world):
    """The world's floor area in m² (`batch_cases --info`: the sum of its spaces, closed rooms included), or None."""
    try:
        binary = find_binary(batch_analysis.TOOL_NAME)
        result = subprocess.run([binary, world, "--info"], capture_output=True, text=True,
                                stdin=subprocess.DEVNULL, timeout=60)
        if result.returncode != 0:
            return None
        return float(json.loads(result.stdout.strip().splitlines()[-1])["floor_area"])
    except (ToolError, OSError, ValueError, KeyError, IndexError, TypeError, subprocess.TimeoutExpired):
        return None


class WorldProgress:
    """One world's tqdm bar on stderr (disabled by --no-progress or when stderr is not a terminal): simulated seconds
    of --max-time, with status_text as postfix. `slots` hands out the bars' lines among the worlds running."""

    def __init__(self, args, world, slots):
        from tqdm import tqdm
        self.slots = slots
        self.slot = slots.get()
        self.bar = tqdm(total=int(args.max_time), desc=world_name(world), position=self.slot, leave=False,
                        file=sys.stderr, disable=True if args.no_progress else None, dynamic_ncols=True,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {n}/{total} s simulated "
                                   "[{elapsed}<{remaining}{postfix}]")
        self.floor_area = None if self.bar.disable else floor_area_of(world)
        self.show(None)

    def show(self, progress):
        if self.bar.disable:
            return
        sim_time = min(int((progress or {}).get("sim_time") or 0), self.bar.total)
        self.bar.set_postfix_str(status_text(progress, self.floor_area), refresh=False)
        if sim_time > self.bar.n:
            self.bar.update(sim_time - self.bar.n)
        else:
            self.bar.refresh()

    def close(self):
        self.bar.close()
        self.slots.put(self.slot)


# --------------------------------------------------------------------------------------------------------
# One world (worker process, with its own ROS master)


class Run:
    """Talks to one exploration_run.launch through rospy: simulated time, the explorer's status, map saving. It
    subscribes to no map (a big OccupancyGrid costs the worker a quarter of a core to read at 10x real time): the
    mapped area comes from the maps it saves."""

    def __init__(self, name):
        import rospy
        from hidden_rooms.msg import ExplorationStatus
        from std_msgs.msg import Bool
        self.rospy = rospy
        rospy.init_node("explore_worlds_" + name.replace("-", "_"), anonymous=True, disable_signals=True)
        self.done = False
        self.free_area = None  # m², of the last saved map
        self.goals = None
        self._run_until = None
        rospy.Subscriber("exploration_done", Bool, self._on_done, queue_size=1)
        rospy.Subscriber("exploration_status", ExplorationStatus, self._on_status, queue_size=1)

    def _on_done(self, message):
        self.done = self.done or message.data

    def _on_status(self, message):
        self.goals = message.goals_chosen

    def sim_time(self):
        return self.rospy.get_time()

    def run_until(self, sim_time):
        """Asks the simulator to hold its clock at `sim_time`; returns its answer (reached, now, finished)."""
        from hidden_rooms.srv import RunUntil
        if self._run_until is None:
            self._run_until = self.rospy.ServiceProxy("run_until", RunUntil, persistent=True)
            self._run_until.wait_for_service(timeout=30.0)
        response = self._run_until(time=sim_time)
        if not response.success:
            raise RuntimeError("run_until: %s" % response.message)
        return response

    def save_map(self, prefix):
        """Writes PREFIX.yaml/.pgm through the mapper's save_map; returns the number of free cells of the map."""
        from hidden_rooms.srv import SaveMap
        service = self.rospy.ServiceProxy("save_map", SaveMap)
        service.wait_for_service(timeout=30.0)
        response = service(prefix=prefix)
        if not response.success:
            raise RuntimeError("save_map: %s" % response.message)
        with open(prefix + ".yaml") as stream:
            resolution = float(yaml.safe_load(stream)["resolution"])
        import cv2
        image = cv2.imread(prefix + ".pgm", cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise RuntimeError("save_map wrote no readable %s.pgm" % prefix)
        free_cells = int(np.count_nonzero(image == 254))  # map_saver's free value
        self.free_area = free_cells * resolution ** 2
        return free_cells


def wait_for_launch(launch, deadline, ready, event):
    """Polls `ready()` every 0.1 s until it is true. RuntimeError naming `event` (what `ready` waits for, e.g. "the
    master came up") when roslaunch exits first or at `deadline` (time.monotonic())."""
    started = time.monotonic()
    while time.monotonic() < deadline:
        if launch.poll() is not None:
            raise RuntimeError("roslaunch exited with code %d before %s" % (launch.returncode, event))
        if ready():
            return
        time.sleep(0.1)
    raise RuntimeError("timed out after %.1f s waiting until %s" % (time.monotonic() - started, event))


def wait_for_master(launch, deadline):
    import rosgraph
    wait_for_launch(launch, deadline, rosgraph.Master("/explore_worlds").is_online, "the master came up")


def wait_for_simulated_time(launch, deadline):
    """Waits until roslaunch has set /use_sim_time true. rospy reads it once, in init_node: a node started on the
    master before the launch file's parameters are set takes wall-clock time for ROS time (the run would stop at
    once with max_time, its simulated time an epoch)."""
    import rosgraph
    master = rosgraph.Master("/explore_worlds")

    def use_sim_time():
        try:
            return master.getParam("/use_sim_time") is True
        except (rosgraph.MasterException, OSError):
            return False  # not set yet

    wait_for_launch(launch, deadline, use_sim_time, "it set /use_sim_time")


def stop_launch(launch):
    if launch.poll() is None:
        launch.send_signal(signal.SIGINT)
        try:
            launch.wait(timeout=SHUTDOWN_TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(launch.pid, signal.SIGKILL)
            launch.wait()


class GrowthStop:
    """The no_growth rule: `update` takes the free cells of each saved map and is true once `patience` maps in a
    row each had less than `growth` (a fraction) more than the map before."""

    def __init__(self, growth, patience):
        self.growth, self.patience = growth, patience
        self.last_free, self.flat = None, 0

    def update(self, free):
        grew = not self.last_free or free - self.last_free >= self.growth * self.last_free
        self.flat = 0 if grew else self.flat + 1
        self.last_free = free
        return self.flat >= self.patience


def explore(args, out_dir, log):
    """Runs the launch until a stop criterion; returns (status, the simulated time its stop rule fired at). Maps go to out_dir."""
    maps_dir = os.path.join(out_dir, "maps")
    os.makedirs(maps_dir, exist_ok=True)
    # The pose_logger continues existing logs (it is respawned with append): those of an earlier, unfinished run go.
    for name in POSE_LOG_NAMES:
        if os.path.exists(os.path.join(out_dir, name)):
            os.remove(os.path.join(out_dir, name))
    command = ["roslaunch", "-p", os.environ["ROS_MASTER_URI"].rsplit(":", 1)[1], "hidden_rooms",
               "exploration_run.launch", "world:=%s" % args.world, "out_dir:=%s" % out_dir,
               "closed_doors:=%s" % args.closed, "realtime_factor:=%g" % args.realtime_factor,
               "seed:=%d" % args.seed, "gui:=%s" % ("true" if args.gui else "false")]
    if args.realtime_factor == 0:
        command.append("run_until:=%g" % LOCKSTEP_CHECK)  # held there until the loop below asks for more
    if args.bag:
        command.append("bag:=%s" % os.path.join(out_dir, "run.bag"))
    launch = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
                              preexec_fn=die_with_parent)
    try:
        wait_for_master(launch, time.monotonic() + MASTER_START_TIMEOUT)
        wait_for_simulated_time(launch, time.monotonic() + MASTER_START_TIMEOUT)
        run = Run(world_name(args.world))
        if run.sim_time() > WALL_CLOCK_EPOCH:
            raise RuntimeError("ROS time reads as wall-clock time (%.0f s): /use_sim_time was not seen"
                               % run.sim_time())
        status, saved = None, 0
        growth_stop = GrowthStop(args.growth, args.patience)
        next_save = args.timeout
        last_sim, last_progress = 0.0, time.monotonic()
        last_written = 0.0
        lockstep = args.realtime_factor == 0
        while status is None:
            if launch.poll() is not None:
                raise RuntimeError("roslaunch exited with code %d during the run (see %s)"
                                   % (launch.returncode, log.name))
            if lockstep:
                # The simulator holds at each check time until the mapper and the explorer have handled its scan,
                # so the stop rules and saved maps see the same state on every run of a seed.
                target = min(next_save, args.max_time, (round(last_sim / LOCKSTEP_CHECK) + 1) * LOCKSTEP_CHECK)
                answer = run.run_until(target)
                while not answer.reached:
                    time.sleep(0.005)
                    if launch.poll() is not None or time.monotonic() - last_progress > STALL_TIMEOUT:
                        break
                    answer = run.run_until(target)
                now = answer.now if answer.reached else run.sim_time()
                done = "/explorer" in answer.finished
            else:
                time.sleep(0.05)  # 0.6 s of simulated time at the default 12x
                now = run.sim_time()
                done = run.done
            if time.monotonic() - last_written >= PROGRESS_INTERVAL:
                write_progress(out_dir, "exploring", now, run.free_area, run.goals, saved)
                last_written = time.monotonic()
            if now > last_sim:
                last_sim, last_progress = now, time.monotonic()
            elif time.monotonic() - last_progress > STALL_TIMEOUT:
                raise RuntimeError("simulated time stopped at %.1f s" % now)
            if done:
                status = "done"
            elif now >= args.max_time:
                status = "max_time"
            elif now >= next_save:
                saved += 1
                free = run.save_map(os.path.join(maps_dir, "map_%03d" % saved))
                if growth_stop.update(free):
                    status = "no_growth"
                next_save += args.timeout
        # The run's simulated time is when its stop rule fired: the simulation goes on while the last map is saved
        # and roslaunch stops (seconds of simulated time at 10x on a busy machine).
        write_progress(out_dir, "finishing", now, run.free_area, run.goals, saved, status)
        run.save_map(os.path.join(out_dir, "map"))
        if lockstep:
            wait_for_pose_logs(out_dir, now - POSE_PERIOD)
        return status, now
    finally:
        stop_launch(launch)


def pose_log_lines(path):
    """The complete lines of a pose log (a line a kill cut has no newline) as (time, line), the header's as
    (None, line); [] when the log does not exist."""
    try:
        with open(path) as log:
            return [(None if line.startswith("#") or not line.strip() else float(line.split()[0]), line)
                    for line in log if line.endswith("\n")]
    except FileNotFoundError:
        return []


def wait_for_pose_logs(out_dir, end):
    """Waits (at most POSE_LOG_TIMEOUT wall seconds) until each pose log has a pose at `end` or later: the clock
    holds, so the logger catches up with a run whose world waited for it to start (its ~lockstep)."""
    def reached(name):
        return any(t is not None and t >= end - 1e-6 for t, _ in pose_log_lines(os.path.join(out_dir, name)))
    deadline = time.monotonic() + POSE_LOG_TIMEOUT
    while time.monotonic() < deadline and not all(reached(name) for name in POSE_LOG_NAMES):
        time.sleep(0.01)


def end_pose_logs(out_dir, end):
    """Drops the poses after `end` (and a line the stop cut) from the pose logs: what the logger wrote while the
    run was being stopped depends on the machine, not on the run."""
    for name in POSE_LOG_NAMES:
        path = os.path.join(out_dir, name)
        if not os.path.isfile(path):
            continue
        kept = [line for t, line in pose_log_lines(path) if t is None or t <= end + 1e-6]
        with open(path + ".partial", "w") as log:
            log.writelines(kept)
        os.replace(path + ".partial", path)


def post_process(args, out_dir, result):
    """translate_doors (doors.yaml, true_rooms.png, exploration.yaml) and the prediction with its scores."""
    translate = [find_binary("translate_doors"), "--environment", args.world, "--closed", args.closed,
                 "--truth", os.path.join(out_dir, "poses_truth.log"),
                 "--estimate", os.path.join(out_dir, "poses_map.log"),
                 "--map", os.path.join(out_dir, "map.yaml"), "--out", out_dir]
    completed = subprocess.run(translate, capture_output=True, text=True)
    if completed.returncode != 0:
        raise RuntimeError(tool_error(completed, "translate_doors"))
    with open(os.path.join(out_dir, "exploration.yaml")) as report_file:
        report = yaml.safe_load(report_file)
    doors = report.get("doors") or []
    result.update(path_length_m=report["path_length"], coverage=report["coverage"],
                  coverage_all_free=report["coverage_all_free"], free_iou=report["free_iou"],
                  worst_door_error_m=max((door["error"] for door in doors), default=""))
    if args.method and doors:
        predict = [find_binary("predict_rooms_offline"), "--map", os.path.join(out_dir, "map.yaml"),
                   "--doors", os.path.join(out_dir, "doors.yaml"), "--method", args.method,
                   "--gt-rooms", os.path.join(out_dir, "true_rooms.png"),
                   "--out", os.path.join(out_dir, "prediction")]
        completed = subprocess.run(predict, capture_output=True, text=True)
        if completed.returncode != 0:
            raise RuntimeError(tool_error(completed, "predict_rooms_offline"))
        with open(os.path.join(out_dir, "prediction", "metrics.yaml")) as metrics_file:
            result["mean_iou"] = round(yaml.safe_load(metrics_file)["mean_iou"], 4)


def load_pose_log(path):
    """Poses of a pose log (pose_log.h) as an N x 4 array: time, x, y, yaw."""
    return np.loadtxt(path, comments="#", ndmin=2)


def draw_trajectory(out_dir):
    """DIR/overlay.png: the prediction's overlay (predicted rooms tinted, true rooms outlined) or the explored map,
    with the robot's estimated trajectory (blue) and the closed doors (red) drawn on it."""
    import cv2
    with open(os.path.join(out_dir, "map.yaml")) as map_file:
        meta = yaml.safe_load(map_file)
    picture_path = os.path.join(out_dir, "prediction", "overlay.png")
    picture = cv2.imread(picture_path if os.path.isfile(picture_path) else
                         os.path.join(out_dir, meta["image"]), cv2.IMREAD_COLOR)
    if picture is None:
        raise RuntimeError("%s: no picture of the map to draw on" % out_dir)
    resolution, origin = float(meta["resolution"]), meta["origin"]

    def pixels(x, y):
        return np.stack([(np.asarray(x) - origin[0]) / resolution,
                         picture.shape[0] - (np.asarray(y) - origin[1]) / resolution], axis=-1)

    poses = load_pose_log(os.path.join(out_dir, "poses_map.log"))
    path = np.round(pixels(poses[:, 1], poses[:, 2])).astype(np.int32)
    cv2.polylines(picture, [path.reshape(-1, 1, 2)], False, (200, 80, 0), 1, cv2.LINE_AA)
    cv2.circle(picture, tuple(int(v) for v in path[0]), 4, (200, 80, 0), -1)
    doors_path = os.path.join(out_dir, "doors.yaml")
    if os.path.isfile(doors_path):
        with open(doors_path) as doors_file:
            doors = yaml.safe_load(doors_file).get("doors") or []
        for door in doors:
            centre = pixels(*door["position"])
            half = 0.5 * door["width"] / resolution
            along_x = door["orientation"] == "O"
            offset = np.array([half, 0.0]) if along_x else np.array([0.0, half])
            a, b = np.round(centre - offset).astype(int), np.round(centre + offset).astype(int)
            cv2.line(picture, tuple(int(v) for v in a), tuple(int(v) for v in b), (0, 0, 220), 3)
            cv2.putText(picture, str(door["id"]), tuple(int(v) for v in b + 3), cv2.FONT_HERSHEY_SIMPLEX, 0.4,
                        (0, 0, 220), 1, cv2.LINE_AA)
    cv2.imwrite(os.path.join(out_dir, "overlay.png"), picture)


def run_worker(args):
    """One world, start to end; writes out_dir/result.json and returns 0 when the run was usable."""
    out_dir = os.path.join(args.out, world_name(args.world))
    os.makedirs(out_dir, exist_ok=True)
    result = {"world": args.world, "status": "failed", "closed_doors": "", "sim_time_s": "", "wall_time_s": "",
              "path_length_m": "", "coverage": "", "coverage_all_free": "", "free_iou": "", "worst_door_error_m": "", "mean_iou": "",
              "message": ""}
    started = time.monotonic()
    write_progress(out_dir, "starting")
    with open(os.path.join(out_dir, "launch.log"), "w") as log:
        try:
            status, sim_time = explore(args, out_dir, log)
            if args.realtime_factor == 0:
                end_pose_logs(out_dir, sim_time - POSE_PERIOD)
            result.update(status=status, sim_time_s=round(sim_time, 1), closed_doors=args.closed)
            result["wall_time_s"] = round(time.monotonic() - started, 1)
            post_process(args, out_dir, result)
            draw_trajectory(out_dir)
        except (RuntimeError, OSError, ToolError) as error:
            result["message"] = str(error)
            result["wall_time_s"] = round(time.monotonic() - started, 1)
    result["settings"] = run_settings(args, args.closed)
    write_json_atomically(os.path.join(out_dir, RESULT_NAME), result)
    return 0 if result["status"] != "failed" else 1


# --------------------------------------------------------------------------------------------------------
# Command line


def parse_arguments(argv):
    parser = ArgumentParser(
        prog="explore_worlds",
        description="Explore simulated worlds with closed doors (simulator + mapper + explorer), save the maps, "
                    "the pose logs and the closed doors in the map frame, and predict the hidden rooms.")
    parser.add_argument("worlds", nargs="+", metavar="WORLDS_DIR|ENV.xml", help="worlds to explore")
    parser.add_argument("--out", required=True, help="output folder (one subfolder per world)")
    parser.add_argument("--closed", default="",
                        help="doors closed in every world: numbers or ids, comma-separated, 'closable', 'all', or "
                             "'random:N' for N of each world's closable doors drawn with --seed (doors with status "
                             "CLOSED in the file are closed anyway)")
    parser.add_argument("--timeout", type=float, default=120.0,
                        help="simulated seconds between saved maps (the thesis's timeout)")
    parser.add_argument("--growth", type=float, default=0.001,
                        help="a saved map with less than this fraction more free cells than the last did not grow "
                             "(a negative value: never stop for it)")
    parser.add_argument("--patience", type=int, default=3,
                        help="stop after this many saved maps in a row that did not grow (1 = the thesis's rule)")
    parser.add_argument("--max-time", type=float, default=1800.0, help="simulated seconds at most per world")
    parser.add_argument("--realtime-factor", type=float, default=12.0,
                        help="simulated seconds per wall second (at 12 the explorer, planning in the background, and "
                             "the mapper keep up on 2 cores, and a campaign, start and stop of each world included, "
                             "goes at 10x or more); 0 = lockstep: the simulator steps on when the mapper "
                             "and the explorer have handled each scan, as fast as the machine allows, and a seed "
                             "gives the same run every time")
    parser.add_argument("--seed", type=int, default=0, help="seed of the simulator and the filter")
    parser.add_argument("--jobs", type=int, default=1, help="worlds explored side by side")
    parser.add_argument("--method", default="default", help="prediction method on the explored map ('' = none)")
    parser.add_argument("--bag", action="store_true", help="also record a bag per world (run.bag)")
    parser.add_argument("--gui", action="store_true", help="show rviz (needs a display; use with --jobs 1)")
    parser.add_argument("--no-progress", action="store_true",
                        help="no progress bars (by default one per running world on stderr when it is a terminal: "
                             "simulated time, mapped area, goals, saved maps)")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    for name in ("timeout", "max_time"):
        if not getattr(args, name) > 0:
            parser.error("--%s must be positive" % name.replace("_", "-"))
    if not args.realtime_factor >= 0:
        parser.error("--realtime-factor must be positive, or 0 for lockstep")
    if args.patience < 1:
        parser.error("--patience must be at least 1")
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    if args.closed.startswith("random:") and not (args.closed[len("random:"):].isdigit() and
                                                   int(args.closed[len("random:"):]) >= 1):
        parser.error("--closed %s: expected random:N with a whole number N >= 1" % args.closed)
    return args


def worker_command(args, world, closed):
    command = [sys.executable, os.path.realpath(sys.argv[0]), world, "--worker", "--out", args.out,
               "--closed", closed, "--timeout", str(args.timeout), "--growth", str(args.growth),
               "--patience", str(args.patience),
               "--max-time", str(args.max_time), "--realtime-factor", str(args.realtime_factor),
               "--seed", str(args.seed), "--method", args.method]
    return command + (["--bag"] if args.bag else []) + (["--gui"] if args.gui else [])


def run_settings(args, closed):
    """What makes two runs of a world the same run (a finished one is kept on a re-run with these)."""
    return {"closed": closed, "timeout": args.timeout, "growth": args.growth, "patience": args.patience,
            "max_time": args.max_time,
            "realtime_factor": args.realtime_factor, "seed": args.seed, "method": args.method, "bag": args.bag}


def finished_result(out_dir, settings):
    """The result of an earlier run of this world with these settings that did not fail, else None."""
    try:
        with open(os.path.join(out_dir, RESULT_NAME)) as result_file:
            result = json.load(result_file)
    except (OSError, ValueError):
        return None
    return result if result.get("status") != "failed" and result.get("settings") == settings else None


def explore_one(args, world, slots):
    """Runs a worker for `world` with its own master, showing its progress (WorldProgress on one of `slots`);
    returns its result dictionary."""
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % free_port(),
               ROS_LOG_DIR=os.path.join(args.out, world_name(world), "ros_log"))
    out_dir = os.path.join(args.out, world_name(world))
    os.makedirs(out_dir, exist_ok=True)
    try:
        closed = closed_doors_of(args.closed, world, args.seed)
    except ToolError as error:
        return {"world": world, "status": "failed", "message": str(error)}
    kept = finished_result(out_dir, run_settings(args, closed))
    if kept is not None:
        kept["message"] = "kept from an earlier run"
        return kept
    progress_path = os.path.join(out_dir, PROGRESS_NAME)
    if os.path.exists(progress_path):  # an earlier, killed run's
        os.remove(progress_path)
    progress = WorldProgress(args, world, slots)
    try:
        with open(os.path.join(out_dir, "worker.log"), "w") as log:
            worker = subprocess.Popen(worker_command(args, world, closed), env=env, stdout=log,
                                      stderr=subprocess.STDOUT, preexec_fn=die_with_parent)
            try:
                while worker.poll() is None:
                    try:
                        worker.wait(timeout=PROGRESS_INTERVAL)
                    except subprocess.TimeoutExpired:
                        progress.show(read_progress(out_dir))
            except BaseException:
                worker.kill()
                worker.wait()
                raise
    finally:
        progress.close()
        if os.path.exists(progress_path):
            os.remove(progress_path)
    try:
        with open(os.path.join(out_dir, RESULT_NAME)) as result_file:
            return json.load(result_file)
    except (OSError, ValueError):
        return {"world": world, "status": "failed", "message": "the worker wrote no result (see %s)"
                % os.path.join(out_dir, "worker.log")}


def main(argv=None):
    args = parse_arguments(sys.argv[1:] if argv is None else argv)
    try:
        worlds = world_files(args.worlds)
        args.out = os.path.realpath(args.out)
        if args.worker:
            args.world = worlds[0]
            return run_worker(args)
        find_binary("translate_doors")
        os.makedirs(args.out, exist_ok=True)
    except ToolError as error:
        print("explore_worlds: error: %s" % error, file=sys.stderr)
        return 2
    from tqdm import tqdm
    results = []
    slots = queue.Queue()  # the progress bars' lines, one per world running
    for slot in range(args.jobs):
        slots.put(slot)
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {pool.submit(explore_one, args, world, slots): world for world in worlds}
        for future in concurrent.futures.as_completed(futures):
            result = future.result()
            results.append(result)
            tqdm.write("explore_worlds: %s: %s, %s s simulated in %s s, coverage %s, mean IoU %s %s"
                       % (world_name(result["world"]), result["status"], result.get("sim_time_s", ""),
                          result.get("wall_time_s", ""), result.get("coverage", ""), result.get("mean_iou", ""),
                          result.get("message", "")), file=sys.stdout)
            sys.stdout.flush()
    order = {world: k for k, world in enumerate(worlds)}
    results.sort(key=lambda result: order.get(result["world"], len(order)))
    summary = os.path.join(args.out, SUMMARY_NAME)
    with open(summary + ".tmp", "w", newline="") as summary_file:
        writer = csv.DictWriter(summary_file, fieldnames=SUMMARY_COLUMNS, extrasaction="ignore", restval="")
        writer.writeheader()
        writer.writerows(results)
    os.replace(summary + ".tmp", summary)
    print("explore_worlds: summary in %s" % summary)
    return 0 if all(result["status"] != "failed" for result in results) else 1
