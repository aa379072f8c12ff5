#!/usr/bin/python3
"""carmen_to_bag: a CARMEN log read (FLASER lines), turned into the bag a ROS robot records (scans, odometry tf, the
laser mount, the true poses) and into a reference map; the odometry drift model; bad logs refused with one line.
With the shared data beside the checkout, both real logs are converted with drifting odometry, mapped by
map_from_bag with config/rbpf_real_laser.ini and scored against their reference maps, with accuracy floors."""
import math
import os
import subprocess
import sys
import tempfile
import unittest

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
sys.path.insert(0, os.path.join(PACKAGE_DIR, "src"))
from hidden_rooms import carmen, package_tools  # noqa: E402

SCRIPT = os.path.join(PACKAGE_DIR, "scripts", "carmen_to_bag")
SHARED_LOGS = os.path.join(os.environ.get("HIDDEN_ROOMS_SHARED_DIR", os.path.join(os.path.dirname(PACKAGE_DIR),
                                                                                  "shared")), "data", "real_logs")


def square_room_log(path, scans=40, no_return=81.83):
    """A robot driving along x through a 10 m x 6 m room (walls at x = -2 and 8, y = -3 and 3), 180 beams."""
    lines = ["# synthetic", "PARAM robot_frontlaser_offset 0.0 nohost 0"]
    for k in range(scans):
        x, y, yaw = 0.1 * k, 0.0, 0.02 * k
        ranges = []
        for i in range(180):
            angle = yaw - 0.5 * math.pi + math.pi * i / 180
            c, s = math.cos(angle), math.sin(angle)
            hits = [t for t in ((8 - x) / c if c > 1e-9 else None, (-2 - x) / c if c < -1e-9 else None,
                                (3 - y) / s if s > 1e-9 else None, (-3 - y) / s if s < -1e-9 else None) if t]
            ranges.append(min(hits) if i % 45 else no_return)  # every 45th beam: no return
        fields = ["FLASER", "180"] + ["%.3f" % r for r in ranges] + ["%.4f" % v for v in (x, y, yaw, x, y, yaw)]
        fields += ["%.3f" % (10.0 + k), "pippo", "%.3f" % (10.0 + k)]
        lines += [" ".join(fields), "ODOM %.4f %.4f %.4f 0 0 0 %.3f pippo %.3f" % (x, y, yaw, 10.0 + k, 10.0 + k)]
    with open(path, "w") as stream:
        stream.write("\n".join(lines) + "\n")


class CarmenLogTest(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp(prefix="hidden_rooms_carmen_")
        self.log = os.path.join(self.folder, "room.log")
        square_room_log(self.log)

    def test_reads_the_flaser_lines_in_time_order(self):
        scans, no_return = carmen.read_log(self.log)
        self.assertEqual(len(scans), 40)
        self.assertEqual(no_return, 81.83)
        self.assertEqual(len(scans[0].ranges), 180)
        self.assertAlmostEqual(scans[3].pose[0], 0.3)
        self.assertAlmostEqual(scans[3].time, 13.0)

    def test_drift_is_zero_without_errors_and_grows_with_the_distance(self):
        poses = [scan.pose for scan in carmen.read_log(self.log)[0]]
        exact = carmen.drifted_odometry(poses, 0.0, 0.0, 0.0, 0.0, seed=1)
        for a, b in zip(exact, poses):
            self.assertAlmostEqual(a[0], b[0], places=9)
            self.assertAlmostEqual(a[2], b[2], places=9)
        scaled = carmen.drifted_odometry(poses, 0.05, 0.0, 0.0, 0.0, seed=1)
        self.assertAlmostEqual(scaled[-1][0], 1.05 * poses[-1][0], places=6)  # 5 % of the 3.9 m driven
        turned = carmen.drifted_odometry(poses, 0.0, 2.0, 0.0, 0.0, seed=1)
        self.assertAlmostEqual(turned[-1][2] - poses[-1][2], math.radians(2.0 * 3.9), places=6)

    def test_bag_holds_what_a_robot_records(self):
        import rosbag
        bag_path = os.path.join(self.folder, "room.bag")
        result = subprocess.run([sys.executable, SCRIPT, self.log, "--out", bag_path, "--reference-map",
                                 os.path.join(self.folder, "reference")], capture_output=True, text=True)
        self.assertEqual(result.returncode, 0, result.stderr)
        counts = {}
        with rosbag.Bag(bag_path) as bag:
            for topic, message, _ in bag.read_messages():
                counts[topic] = counts.get(topic, 0) + 1
                if topic == carmen.SCAN_TOPIC:
                    scan = message
        self.assertEqual(counts, {"/tf_static": 1, "/tf": 40, carmen.SCAN_TOPIC: 40, carmen.TRUTH_TOPIC: 40})
        self.assertEqual(len(scan.ranges), 180)
        self.assertAlmostEqual(scan.angle_min, -0.5 * math.pi, places=6)
        self.assertAlmostEqual(scan.angle_increment, math.pi / 180, places=6)
        self.assertTrue(math.isinf(scan.ranges[0]), "a beam without return is +inf (REP 117)")
        # The reference map: the walls the forward laser saw occupied (x from 0 to 8, y from -3 to 3, plus a metre
        # around), the room's inside free.
        with open(os.path.join(self.folder, "reference.pgm"), "rb") as stream:
            data = stream.read()
        header = data.split(b"\n", 3)
        width, height = map(int, header[1].split())
        self.assertAlmostEqual(width * 0.05, 10.0, delta=0.2)
        self.assertAlmostEqual(height * 0.05, 8.0, delta=0.2)
        pixels = header[3]
        self.assertGreater(pixels.count(254), 0.7 * 8 * 6 / 0.05 ** 2)
        self.assertGreater(pixels.count(0), (8 + 6 + 6) / 0.05 * 0.8)

    def test_bad_logs_and_options_exit_2_with_one_line(self):
        broken = os.path.join(self.folder, "broken.log")
        with open(broken, "w") as stream:
            stream.write("FLASER 180 1 2 3\n")
        empty = os.path.join(self.folder, "empty.log")
        open(empty, "w").close()
        cases = [([broken], "broken.log:1: malformed FLASER line"), ([empty], "fewer than two FLASER lines"),
                 ([os.path.join(self.folder, "missing.log")], "cannot read the log"),
                 ([self.log, "--odometry-noise", "0.05,2"], "four numbers"), ([self.log, "--bogus"], "--bogus")]
        for arguments, message in cases:
            out = os.path.join(self.folder, "out.bag")
            result = subprocess.run([sys.executable, SCRIPT] + arguments + ["--out", out], capture_output=True,
                                    text=True)
            self.assertEqual(result.returncode, 2, arguments)
            self.assertEqual(len(result.stderr.strip().splitlines()), 1, result.stderr)
            self.assertIn(message, result.stderr)
            self.assertFalse(os.path.exists(out))


# Floors of free IoU and walls within 2 cells on the drifted bags with config/rbpf_real_laser.ini. Intel: the
# targets of the real-data issue (0.85, 0.90); measured 0.908 / 0.954. ACES: measured 0.827 / 0.862, where the
# same ini without loop closure (loop_min_travel = 0) maps 0.768 / 0.491.
REAL_LOG_FLOORS = {"intel": (0.85, 0.90), "aces": (0.78, 0.75)}


class RealLogsTest(unittest.TestCase):
    """Both real logs through carmen_to_bag and map_from_bag --reference-map, then rooms of the map hidden and
    predicted (the real-data smoke test of the whole chain)."""

    def test_both_logs_map_and_score(self):
        if not os.path.isdir(SHARED_LOGS):
            if os.environ.get("HIDDEN_ROOMS_REQUIRE_SHARED") == "1":
                self.fail("%s is missing" % SHARED_LOGS)
            self.skipTest("no shared data beside the checkout")
        map_from_bag = package_tools.find_binary("map_from_bag")
        folder = tempfile.mkdtemp(prefix="hidden_rooms_real_logs_")
        predicted = 0
        for name in ("intel", "aces"):
            log = os.path.join(SHARED_LOGS, "%s-corrected.log.gz" % name)
            bag, reference = os.path.join(folder, name + ".bag"), os.path.join(folder, name + "_reference")
            subprocess.run([sys.executable, SCRIPT, log, "--out", bag, "--reference-map", reference,
                            "--odometry-noise", "0.05,2,0.01,0.5"], check=True, capture_output=True)
            trajectory = os.path.join(folder, name + "_trajectory.log")
            result = subprocess.run([map_from_bag, bag, "--out", os.path.join(folder, name), "--quiet",
                                     "--reference-map", reference + ".yaml", "--trajectory", trajectory,
                                     "--config", os.path.join(PACKAGE_DIR, "config", "rbpf_real_laser.ini")],
                                    capture_output=True, text=True)
            self.assertEqual(result.returncode, 0, result.stderr)
            figures = dict(line.split(": ", 1) for line in result.stdout.splitlines() if ": " in line)
            print("%s, drifted odometry: %s" % (name, ", ".join("%s %s" % (key, figures[key]) for key in (
                "free_iou", "walls_within_2_cells", "trajectory_rmse_m", "relative_translation_per_metre"))))
            self.assertEqual(int(figures["scans"]), {"intel": 910, "aces": 440}[name])
            with open(trajectory) as stream:
                poses = [line for line in stream if not line.startswith("#")]
            self.assertEqual(len(poses), int(figures["scans"]), "one SLAM pose per scan")
            for key, floor in zip(("free_iou", "walls_within_2_cells"), REAL_LOG_FLOORS[name]):
                self.assertGreaterEqual(float(figures[key]), floor, "%s %s" % (name, key))
            predicted += self.predict_hidden_rooms(name, os.path.join(folder, name))
        self.assertGreaterEqual(predicted, 1, "no real map had a room to hide")

    def predict_hidden_rooms(self, name, map_prefix):
        """The whole chain on the real map: its rooms behind one doorway hidden (hide_rooms) and predicted, with a
        floor on the mean IoU. Returns 1, or 0 for a map without such a room (ACES: its robot kept to the
        corridors, and the rooms show only as laser fans through the doors)."""
        case, prediction = map_prefix + "_case", map_prefix + "_prediction"
        hidden = subprocess.run([package_tools.find_binary("hide_rooms"), map_prefix + ".yaml", "--out", case],
                                capture_output=True, text=True)
        if hidden.returncode == 2 and "has no closable room" in hidden.stderr:
            print("%s: %s" % (name, hidden.stderr.strip()))
            return 0
        self.assertEqual(hidden.returncode, 0, hidden.stderr)
        result = subprocess.run([package_tools.find_binary("predict_rooms_offline"), "--map", case + "/map.yaml",
                                 "--doors", case + "/doors.yaml", "--method", "default", "--out", prediction,
                                 "--gt-rooms", case + "/gt_rooms.png"], capture_output=True, text=True)
        self.assertEqual(result.returncode, 0, result.stderr)
        print("%s, hidden rooms predicted: %s" % (name, " ".join(
            line.strip() for line in result.stdout.splitlines() if "IoU" in line)))
        with open(os.path.join(prediction, "metrics.yaml")) as stream:
            metrics = dict(line.split(": ", 1) for line in stream if line.startswith(("mean_iou", "iou_total")))
        self.assertGreaterEqual(len(hidden.stdout.splitlines()) - 1, 3, "rooms hidden")
        self.assertGreaterEqual(float(metrics["mean_iou"]), 0.4)
        return 1


if __name__ == "__main__":
    unittest.main()
