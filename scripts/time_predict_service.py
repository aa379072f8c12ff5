#!/usr/bin/python3
"""Times predict_rooms end to end on a closed-door benchmark case.

    scripts/time_predict_service.py CASE_DIR [--method default] [--repeats 20]

Starts `roslaunch hidden_rooms predict.launch` on CASE_DIR/map.yaml and CASE_DIR/doors.yaml (its own roscore on a
free port), waits for the service, then calls it --repeats times with every door of the case: once with the map
taken from the node's `map` topic (empty request map), once with the map sent in the request. Prints the wall
time per call (service round trip, as a caller sees it: serialisation, transport, prediction, conversion) and
the method's own computation time. Needs the workspace sourced (source devel/setup.bash).
"""
import argparse
import os
import socket
import statistics
import subprocess
import sys
import time

import yaml


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("case_dir", help="benchmark case: map.yaml, doors.yaml")
    parser.add_argument("--method", default="default")
    parser.add_argument("--repeats", type=int, default=20)
    args = parser.parse_args()
    # Absolute paths: roslaunch starts the nodes in ROS_HOME, not here.
    map_yaml = os.path.abspath(os.path.join(args.case_dir, "map.yaml"))
    doors_yaml = os.path.abspath(os.path.join(args.case_dir, "doors.yaml"))
    for path in (map_yaml, doors_yaml):
        if not os.path.isfile(path):
            sys.exit("time_predict_service: %s: not found" % path)

    port = free_port()
    os.environ["ROS_MASTER_URI"] = "http://localhost:%d" % port
    launch = subprocess.Popen(["roslaunch", "-p", str(port), "hidden_rooms", "predict.launch", "map:=" + map_yaml,
                               "doors:=" + doors_yaml, "method:=" + args.method],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        import rosgraph
        import rospy
        from geometry_msgs.msg import Point
        from hidden_rooms.msg import ClosedDoor
        from hidden_rooms.srv import PredictRooms, PredictRoomsRequest
        from nav_msgs.msg import OccupancyGrid

        deadline = time.time() + 60.0
        while not rosgraph.Master("/time_predict_service").is_online():
            if time.time() > deadline or launch.poll() is not None:
                sys.exit("time_predict_service: roslaunch did not start a master")
            time.sleep(0.2)
        rospy.init_node("time_predict_service", anonymous=True, disable_signals=True)
        rospy.wait_for_service("predict_rooms", timeout=60.0)
        predict = rospy.ServiceProxy("predict_rooms", PredictRooms, persistent=True)
        the_map = rospy.wait_for_message("map", OccupancyGrid, timeout=60.0)
        # The node has the map once it has predicted on it (predict_on_map in config/predict.yaml).
        rospy.wait_for_message("predicted_map", OccupancyGrid, timeout=60.0)
        with open(doors_yaml) as stream:
            entries = yaml.safe_load(stream)["doors"]
        doors = [ClosedDoor(id=d["id"], position=Point(x=d["position"][0], y=d["position"][1]), width=d["width"],
                            orientation=ClosedDoor.ALONG_X if d["orientation"] == "O" else ClosedDoor.ALONG_Y)
                 for d in entries]
        print("%s: %d doors, map %dx%d cells, method %s, %d calls each" % (
            args.case_dir, len(doors), the_map.info.width, the_map.info.height, args.method, args.repeats))
        for label, request_map in (("map from the topic", OccupancyGrid()), ("map in the request", the_map)):
            request = PredictRoomsRequest(doors=doors, map=request_map, method=args.method)
            predict(request)  # warm-up (first connection)
            walls, computes = [], []
            for _ in range(args.repeats):
                start = time.perf_counter()
                response = predict(request)
                walls.append(time.perf_counter() - start)
                if not response.success:
                    sys.exit("time_predict_service: %s" % response.message)
                computes.append(response.computation_time)
            walls.sort()
            print("  %-19s end to end: median %.3f s, max %.3f s; prediction itself: median %.3f s" % (
                label + ":", statistics.median(walls), walls[-1], statistics.median(computes)))
        predict.close()
    finally:
        os.killpg(launch.pid, 2)
        launch.wait(timeout=30)


if __name__ == "__main__":
    main()
