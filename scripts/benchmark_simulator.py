#!/usr/bin/python3
"""Real-time factor of the simulator, headless, with the default laser (1081 beams, 270 degrees, 30 m, 10 Hz).

For each world:
  1. the core without ROS (`benchmark_simulation`): scripted reactive drive for --sim-seconds with each laser
     caster (Box2D ray casts, grid DDA), their time per scan and their agreement;
  2. the `simulator` node (simulation.launch, realtime_factor 0) on its own roscore, driven by this script
     (the same reactive drive on base_scan -> cmd_vel) for --ros-seconds of wall time: simulated seconds per
     wall second from the scans' stamps.

Default worlds: the largest shipped world (worlds/large_2.xml) and the largest school of the shared data
(../shared/data/environments/school/stjosephscatholichighschool.xml) when it is there. Target: >= 100x.

  scripts/benchmark_simulator.py [--worlds A.xml,B.xml] [--sim-seconds 300] [--ros-seconds 20]
"""
import argparse
import math
import os
import signal
import socket
import subprocess
import sys
import time

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))


def default_worlds():
    worlds = [os.path.join(PACKAGE_DIR, "worlds", "large_2.xml")]
    shared = os.environ.get("HIDDEN_ROOMS_SHARED_DIR", os.path.join(PACKAGE_DIR, "..", "shared"))
    school = os.path.join(shared, "data", "environments", "school", "stjosephscatholichighschool.xml")
    if os.path.isfile(school):
        worlds.append(os.path.realpath(school))
    return worlds


def core_benchmark(world, sim_seconds):
    output = subprocess.run(["rosrun", "hidden_rooms", "benchmark_simulation", world, "--sim-seconds", str(sim_seconds)],
                            check=True, stdout=subprocess.PIPE, universal_newlines=True).stdout
    import yaml
    return yaml.safe_load(output)


def free_port():
    with socket.socket() as sock:
        sock.bind(("localhost", 0))
        return sock.getsockname()[1]


def drive_command(ranges, angle_min, increment, state):
    """The reactive drive of benchmark_simulation: forward, steer to the open side, turn in place when blocked."""
    ahead, left, right = 30.0, 0.0, 0.0
    for k, r in enumerate(ranges):
        angle = angle_min + k * increment
        if abs(angle) < 0.45:
            ahead = min(ahead, r)
        if 0.3 < angle < 1.6:
            left += min(r, 5.0)
        if -1.6 < angle < -0.3:
            right += min(r, 5.0)
    if state["turning"] and ahead > 1.5:
        state["turning"] = 0
    if not state["turning"] and ahead < 0.9:
        state["turning"] = 1 if left >= right else -1
    if state["turning"]:
        return 0.0, 1.2 * state["turning"]
    balance = (left - right) / max(left + right, 1.0)
    return min(0.7, 0.35 * ahead), max(-0.6, min(0.6, 2.0 * balance))


def ros_benchmark(world, wall_seconds):
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port)
    launch = subprocess.Popen(["roslaunch", "-p", str(port), "hidden_rooms", "simulation.launch", "world:=" + world,
                               "realtime_factor:=0", "seed:=1"], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    try:
        os.environ["ROS_MASTER_URI"] = env["ROS_MASTER_URI"]
        import rospy
        from geometry_msgs.msg import Twist
        from sensor_msgs.msg import LaserScan
        import rosgraph
        deadline = time.time() + 60
        while not rosgraph.is_master_online(master_uri=env["ROS_MASTER_URI"]):  # wait for the master
            if time.time() > deadline:
                raise RuntimeError("no roscore on port %d" % port)
            time.sleep(0.2)
        rospy.init_node("benchmark_simulator", anonymous=True, disable_signals=True)
        publisher = rospy.Publisher("cmd_vel", Twist, queue_size=1)
        stamps = []
        state = {"turning": 0}

        def on_scan(scan):
            stamps.append((time.time(), scan.header.stamp.to_sec()))
            linear, angular = drive_command(scan.ranges, scan.angle_min, scan.angle_increment, state)
            command = Twist()
            command.linear.x, command.angular.z = linear, angular
            publisher.publish(command)

        rospy.Subscriber("base_scan", LaserScan, on_scan, queue_size=1, buff_size=2 ** 20)
        deadline = time.time() + 60
        while not stamps and time.time() < deadline:
            time.sleep(0.05)
        if not stamps:
            raise RuntimeError("no scan from the simulator")
        time.sleep(2.0)  # warm up
        first = stamps[-1]
        time.sleep(wall_seconds)
        last = stamps[-1]
        return (last[1] - first[1]) / (last[0] - first[0])
    finally:
        launch.send_signal(signal.SIGINT)
        try:
            launch.wait(timeout=20)
        except subprocess.TimeoutExpired:
            launch.kill()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--worlds", help="comma-separated environment XMLs (default: see above)")
    parser.add_argument("--sim-seconds", type=float, default=300.0, help="simulated seconds per caster (core)")
    parser.add_argument("--ros-seconds", type=float, default=20.0, help="wall seconds of the node run; 0 = skip")
    parser.add_argument("--ros-child", help=argparse.SUPPRESS)  # one node run in its own process (rospy inits once)
    args = parser.parse_args()
    if args.ros_child:
        print(ros_benchmark(args.ros_child, args.ros_seconds))
        return 0
    worlds = args.worlds.split(",") if args.worlds else default_worlds()
    failed = False
    for world in worlds:
        world = os.path.realpath(world)
        core = core_benchmark(world, args.sim_seconds)
        print("%s" % world)
        print("  core, scripted drive %.0f s: real-time factor box2d %.0fx, grid %.0fx; %d static fixtures"
              % (args.sim_seconds, core["box2d"]["realtime_factor"], core["grid"]["realtime_factor"],
                 core["static_fixtures"]))
        print("  casters: box2d %d us/scan, grid %d us/scan; agreement within 5 cm %.1f%%, same wall at a grazing"
              " angle %.1f%%, disagree %.2f%%, median |difference| %.1f mm"
              % (core["scan_microseconds_median"]["box2d"], core["scan_microseconds_median"]["grid"],
                 100 * core["agreement"]["within_5cm"], 100 * core["agreement"]["same_surface_grazing"],
                 100 * core["agreement"]["disagree"], 1000 * core["agreement"]["median_abs_difference_m"]))
        factors = [core["box2d"]["realtime_factor"]]
        if args.ros_seconds > 0:
            factor = float(subprocess.run([sys.executable, os.path.realpath(__file__), "--ros-child", world,
                                           "--ros-seconds", str(args.ros_seconds)], check=True,
                                          stdout=subprocess.PIPE, universal_newlines=True).stdout.split()[-1])
            factors.append(factor)
            print("  simulator node (ROS, realtime_factor 0, %.0f s wall): %.0fx real time" % (args.ros_seconds, factor))
        if min(factors) < 100:
            failed = True
            print("  BELOW the 100x target")
        sys.stdout.flush()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
