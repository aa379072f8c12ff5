"""CARMEN laser logs (the format of most classic 2D SLAM datasets) as a ROS user's robot would record them.

`carmen_to_bag LOG --out BAG` writes the log's FLASER scans as sensor_msgs/LaserScan on `base_scan` (frame
`base_laser_link`, no-return beams +inf as REP 117 asks), the odometry as /tf `odom -> base_link` (the log's own,
or corrupted with accumulated drift by --odometry-noise), the laser mount on /tf_static and the log's corrected
poses as nav_msgs/Odometry on `base_pose_ground_truth`, the reference trajectory `map_from_bag` scores against.
`--reference-map PREFIX` also writes the map drawn from the corrected poses (PREFIX.yaml + PREFIX.pgm), the
reference map of `map_from_bag --reference-map`.
"""
import gzip
import math
import os

import numpy as np

from hidden_rooms.package_tools import ArgumentParser, ToolError

SCAN_TOPIC = "base_scan"
TRUTH_TOPIC = "base_pose_ground_truth"
ODOM_FRAME = "odom"
BASE_FRAME = "base_link"
LASER_FRAME = "base_laser_link"
TRUTH_FRAME = "world"


class Scan:
    """One FLASER line: time (s), ranges (m, counter-clockwise from -90 degrees), the corrected pose (x, y, yaw)."""

    def __init__(self, time, ranges, pose):
        self.time = time
        self.ranges = ranges
        self.pose = pose


def read_log(path):
    """The FLASER scans of a CARMEN log (plain or gzipped) in time order, and the range that means "no return"
    (the largest value of the log). Raises ToolError naming the file and line for anything unreadable."""
    opener = gzip.open if path.endswith(".gz") else open
    scans = []
    try:
        with opener(path, "rt", errors="replace") as stream:
            for number, line in enumerate(stream, 1):
                fields = line.split()
                if not fields or fields[0] != "FLASER":
                    continue
                try:
                    count = int(fields[1])
                    if count < 2 or len(fields) < count + 9:
                        raise ValueError("%d ranges announced, %d fields" % (count, len(fields)))
                    values = [float(value) for value in fields[2:count + 2] + fields[count + 2:count + 5] +
                              [fields[count + 8]]]
                except (ValueError, IndexError) as error:
                    raise ToolError("%s:%d: malformed FLASER line (%s)" % (path, number, error))
                if not all(math.isfinite(value) for value in values):
                    raise ToolError("%s:%d: FLASER line with a value that is not finite" % (path, number))
                ranges, pose, time = values[:count], tuple(values[count:count + 3]), values[count + 3]
                if scans and len(ranges) != len(scans[0].ranges):
                    raise ToolError("%s:%d: %d ranges where the log's first scan has %d" % (
                        path, number, len(ranges), len(scans[0].ranges)))
                scans.append(Scan(time, ranges, pose))
    except OSError as error:
        raise ToolError("%s: cannot read the log: %s" % (path, error))
    if len(scans) < 2:
        raise ToolError("%s: fewer than two FLASER lines" % path)
    scans.sort(key=lambda scan: scan.time)
    no_return = max(max(scan.ranges) for scan in scans)
    return scans, no_return


def relative(a, b):
    """The motion from pose a to pose b in a's frame: (dx, dy, dyaw)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2])


def compose(a, d):
    c, s = math.cos(a[2]), math.sin(a[2])
    return a[0] + c * d[0] - s * d[1], a[1] + s * d[0] + c * d[1], wrap(a[2] + d[2])


def wrap(angle):
    return math.atan2(math.sin(angle), math.cos(angle))


def drifted_odometry(poses, scale_error, yaw_drift_deg_per_m, sigma_per_m, sigma_deg_per_m, seed):
    """Odometry integrated from the true motions with a systematic scale error (fraction of the distance), a
    systematic heading drift (degrees per metre driven) and zero-mean noise (standard deviations per metre), as
    wheel odometry drifts; starts at the first true pose."""
    random = np.random.default_rng(seed)
    odometry = [poses[0]]
    for a, b in zip(poses, poses[1:]):
        dx, dy, dyaw = relative(a, b)
        distance = math.hypot(dx, dy)
        noise = random.normal(size=3)
        step = (dx * (1.0 + scale_error) + noise[0] * sigma_per_m * distance,
                dy * (1.0 + scale_error) + noise[1] * sigma_per_m * distance,
                dyaw + math.radians(yaw_drift_deg_per_m * distance + noise[2] * sigma_deg_per_m * distance))
        odometry.append(compose(odometry[-1], step))
    return odometry


def beam_angles(count):
    """CARMEN's front laser: `count` beams spread over 180 degrees counter-clockwise from -90 (1 degree apart for
    180 beams)."""
    increment = math.pi / count
    return -0.5 * math.pi, increment


def write_bag(scans, no_return, odometry, path):
    """The bag a robot with this laser and odometry would record (see the module's docstring)."""
    import rosbag
    import rospy
    from geometry_msgs.msg import TransformStamped
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import LaserScan
    from tf2_msgs.msg import TFMessage

    def transform(stamp, parent, child, pose):
        message = TransformStamped()
        message.header.stamp = stamp
        message.header.frame_id = parent
        message.child_frame_id = child
        message.transform.translation.x, message.transform.translation.y = pose[0], pose[1]
        message.transform.rotation.z, message.transform.rotation.w = math.sin(0.5 * pose[2]), math.cos(0.5 * pose[2])
        return message

    angle_min, increment = beam_angles(len(scans[0].ranges))
    temporary = path + ".partial%d" % os.getpid()
    try:
        with rosbag.Bag(temporary, "w") as bag:
            first = rospy.Time.from_sec(scans[0].time)
            bag.write("/tf_static", TFMessage([transform(first, BASE_FRAME, LASER_FRAME, (0.0, 0.0, 0.0))]), first)
            for sequence, (scan, pose) in enumerate(zip(scans, odometry)):
                stamp = rospy.Time.from_sec(scan.time)
                bag.write("/tf", TFMessage([transform(stamp, ODOM_FRAME, BASE_FRAME, pose)]), stamp)
                truth = Odometry()
                truth.header.stamp = stamp
                truth.header.frame_id = TRUTH_FRAME
                truth.child_frame_id = BASE_FRAME
                truth.pose.pose.position.x, truth.pose.pose.position.y = scan.pose[0], scan.pose[1]
                truth.pose.pose.orientation.z = math.sin(0.5 * scan.pose[2])
                truth.pose.pose.orientation.w = math.cos(0.5 * scan.pose[2])
                bag.write(TRUTH_TOPIC, truth, stamp)
                message = LaserScan()
                message.header.stamp = stamp
                message.header.seq = sequence
                message.header.frame_id = LASER_FRAME
                message.angle_min = angle_min
                message.angle_increment = increment
                message.angle_max = angle_min + increment * (len(scan.ranges) - 1)
                message.range_min = 0.0
                message.range_max = no_return
                message.ranges = [math.inf if value >= no_return else value for value in scan.ranges]
                bag.write(SCAN_TOPIC, message, stamp)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def reference_map(scans, no_return, resolution, max_range):
    """The map drawn from the corrected poses and the beams with a return within `max_range`: per cell, beams
    ending there (hits) against beams passing through (misses); occupied where hits >= misses, free where beams
    passed more often, unknown elsewhere (beams without a return mark nothing: through glass and open doors they
    would paint free space outside the building). Returns (cells as map_server values 0 / 254 / 205, origin)."""
    angle_min, increment = beam_angles(len(scans[0].ranges))
    angles = angle_min + increment * np.arange(len(scans[0].ranges))
    ends, starts = [], []
    for scan in scans:
        ranges = np.asarray(scan.ranges)
        returned = ranges < min(no_return, max_range)
        world = scan.pose[2] + angles[returned]
        ends.append(np.stack([scan.pose[0] + ranges[returned] * np.cos(world),
                              scan.pose[1] + ranges[returned] * np.sin(world)], axis=1))
        starts.append(np.repeat([[scan.pose[0], scan.pose[1]]], np.count_nonzero(returned), axis=0))
    ends, starts = np.concatenate(ends), np.concatenate(starts)
    low = np.minimum(ends.min(axis=0), starts.min(axis=0)) - 1.0
    high = np.maximum(ends.max(axis=0), starts.max(axis=0)) + 1.0
    origin = np.floor(low / resolution) * resolution
    width, height = (np.ceil((high - origin) / resolution)).astype(int)
    hits = np.zeros((height, width), np.int32)
    misses = np.zeros((height, width), np.int32)

    def cells(points):
        index = np.floor((points - origin) / resolution).astype(int)
        return index[:, 1], index[:, 0]  # rows from the bottom, columns

    for start, end in zip(starts, ends):
        length = math.hypot(end[0] - start[0], end[1] - start[1])
        samples = max(2, int(length / (0.5 * resolution)))
        t = np.linspace(0.0, 1.0, samples, endpoint=False)
        points = start[None, :] + t[:, None] * (end - start)[None, :]
        rows, cols = cells(points)
        misses[rows, cols] += 1
        row, col = cells(end[None, :])
        hits[row, col] += 1
    passed = np.maximum(misses - hits, 0)
    grid = np.full((height, width), 205, np.uint8)
    grid[(misses > 0) & (hits == 0)] = 254
    grid[(hits > 0) & (hits >= passed)] = 0
    grid[(hits > 0) & (hits < passed)] = 254
    return grid[::-1], (float(origin[0]), float(origin[1]))


def write_map(grid, origin, resolution, prefix):
    """PREFIX.pgm + PREFIX.yaml as map_saver writes them."""
    folder = os.path.dirname(os.path.abspath(prefix))
    os.makedirs(folder, exist_ok=True)
    image = prefix + ".pgm"
    with open(image + ".partial", "wb") as stream:
        stream.write(b"P5\n%d %d\n255\n" % (grid.shape[1], grid.shape[0]) + grid.tobytes())
    os.replace(image + ".partial", image)
    with open(prefix + ".yaml.partial", "w") as stream:
        stream.write("image: %s\nresolution: %g\norigin: [%.6f, %.6f, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
                     "free_thresh: 0.196\n" % (os.path.basename(image), resolution, origin[0], origin[1]))
    os.replace(prefix + ".yaml.partial", prefix + ".yaml")


def parse_noise(text):
    try:
        values = [float(value) for value in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 4 or not all(math.isfinite(value) and value >= 0.0 for value in values):
        raise ToolError("--odometry-noise %s: give SCALE,DEG_PER_M,SIGMA_PER_M,SIGMA_DEG_PER_M, four numbers >= 0 "
                        "(for example 0.05,2,0.01,0.5)" % text)
    return values


def main(argv=None):
    import sys
    parser = ArgumentParser(prog="carmen_to_bag", description=__doc__.split("\n\n")[0])
    parser.add_argument("log", help="CARMEN log (FLASER lines; .gz read as gzip)")
    parser.add_argument("--out", required=True, help="bag to write")
    parser.add_argument("--odometry-noise", metavar="SCALE,DEG_PER_M,SIGMA_PER_M,SIGMA_DEG_PER_M",
                        help="odometry from the corrected poses with drift: scale error (fraction of the distance), "
                             "heading drift (degrees per metre), noise (metres and degrees per metre); default: "
                             "the log's own odometry")
    parser.add_argument("--seed", type=int, default=0, help="seed of the odometry noise")
    parser.add_argument("--reference-map", metavar="PREFIX", help="also write the map drawn from the corrected "
                        "poses to PREFIX.yaml + PREFIX.pgm")
    parser.add_argument("--resolution", type=float, default=0.05, help="of the reference map, metres")
    parser.add_argument("--max-range", type=float, default=20.0,
                        help="the reference map takes the beams with a return closer than this, metres (default 20)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        if not (args.resolution > 0.0 and args.max_range > 0.0):
            raise ToolError("--resolution and --max-range must be positive")
        noise = parse_noise(args.odometry_noise) if args.odometry_noise else None
        scans, no_return = read_log(args.log)
        poses = [scan.pose for scan in scans]
        odometry = drifted_odometry(poses, *noise, seed=args.seed) if noise else poses
        write_bag(scans, no_return, odometry, args.out)
        if args.reference_map:
            grid, origin = reference_map(scans, no_return, args.resolution, args.max_range)
            write_map(grid, origin, args.resolution, args.reference_map)
    except ToolError as error:
        print("carmen_to_bag: error: %s" % error, file=sys.stderr)
        return 2
    distance = sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(poses, poses[1:]))
    end_error = math.hypot(odometry[-1][0] - poses[-1][0], odometry[-1][1] - poses[-1][1])
    print("carmen_to_bag: %d scans of %d beams, %.0f s, %.1f m driven, odometry %s (end %.2f m off) -> %s" % (
        len(scans), len(scans[0].ranges), scans[-1].time - scans[0].time, distance,
        "drifted" if noise else "as logged", end_error, args.out))
    return 0
