#!/usr/bin/python3
"""The install space (`catkin_make install`) works on its own: every program of the devel space but the tests is
installed, the launch files resolve, the demo's prediction runs from it (the offline tool and the ROS service),
the Python tools start, and a package built against it (test/downstream/) calls the predictor and uses the
messages. Every command runs in a clean environment with only the install space's setup.bash sourced.

Run by scripts/test.sh after `catkin_make install`, with HIDDEN_ROOMS_INSTALL_SPACE set to the install space and
the devel space sourced (the devel space says which programs must be installed)."""
import glob
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import unittest
import xml.etree.ElementTree as ElementTree

import yaml

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
DOWNSTREAM_PACKAGE = os.path.join(PACKAGE_DIR, "test", "downstream", "hidden_rooms_downstream_check")
# The demo's case (scripts/demo.sh): world, closed doors, method.
DEMO_WORLD, DEMO_DOORS, DEMO_METHOD = "small_1.xml", "3,5,8", "default"
# bash -c script: $1 the install space, the rest the command. setup.bash reads the positional parameters (it
# passes them to catkin's _setup_util.py): it is sourced without any.
SOURCE_AND_RUN = 'install="$1"; shift; command=("$@"); set --; source "$install/setup.bash" && exec "${command[@]}"'


def free_port():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


class InstallSpace(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.install = os.environ.get("HIDDEN_ROOMS_INSTALL_SPACE", "")
        if not os.path.isfile(os.path.join(cls.install, "setup.bash")):
            raise AssertionError("HIDDEN_ROOMS_INSTALL_SPACE=%r is not an install space (run catkin_make install "
                                 "and set it; scripts/test.sh does)" % cls.install)
        cls.share = os.path.join(cls.install, "share", "hidden_rooms")
        cls.folder = tempfile.mkdtemp(prefix="install_space_test_")
        # The demo's world with its doors closed and the rooms behind them hidden, by the installed tool.
        cls.case = os.path.join(cls.folder, "case")
        cls.run_installed(["rosrun", "hidden_rooms", "render_environment",
                           os.path.join(cls.share, "worlds", DEMO_WORLD), "--out", cls.case, "--closed",
                           DEMO_DOORS, "--hide-closed-rooms"], check=True)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.folder, ignore_errors=True)

    @classmethod
    def environment(cls, **extra):
        env = {"HOME": os.environ.get("HOME", cls.folder), "PATH": "/usr/bin:/bin", "LANG": "C.UTF-8",
               "ROS_HOME": os.path.join(cls.folder, "ros_home")}
        env.update(extra)
        return env

    @classmethod
    def run_installed(cls, command, check=False, timeout=300, cwd=None, **extra_env):
        """Runs `command` with only the install space sourced; returns the CompletedProcess."""
        result = subprocess.run(["bash", "-c", SOURCE_AND_RUN, "bash", cls.install] + command,
                                env=cls.environment(**extra_env),
                                cwd=cwd, capture_output=True, text=True, timeout=timeout)
        if check and result.returncode != 0:
            raise AssertionError("%s: exit %d\n%s%s" % (" ".join(command), result.returncode, result.stdout,
                                                        result.stderr))
        return result

    def test_every_program_but_the_tests_is_installed(self):
        devel = [path for path in os.environ.get("CMAKE_PREFIX_PATH", "").split(":")
                 if os.path.isdir(os.path.join(path, "lib", "hidden_rooms"))]
        self.assertTrue(devel, "no devel space with lib/hidden_rooms on CMAKE_PREFIX_PATH")
        built = {os.path.basename(path) for path in glob.glob(os.path.join(devel[0], "lib", "hidden_rooms", "*"))
                 if os.access(path, os.X_OK) and not os.path.basename(path).startswith(("test_", "fuzz_"))}
        installed = set(os.listdir(os.path.join(self.install, "lib", "hidden_rooms")))
        self.assertFalse(built - installed, "built but not installed")
        found = self.run_installed(["rospack", "find", "hidden_rooms"], check=True).stdout.strip()
        self.assertEqual(os.path.realpath(found), os.path.realpath(self.share))
        for folder, pattern in (("launch_files", "*.launch"), ("config", "*.rviz"), ("config", "*.yaml"),
                                ("config", "*.ini"), ("worlds", "*.xml")):
            shipped = {os.path.basename(path) for path in glob.glob(os.path.join(PACKAGE_DIR, folder, pattern))}
            copied = {os.path.basename(path) for path in glob.glob(os.path.join(self.share, folder, pattern))}
            self.assertTrue(shipped, "%s/%s" % (folder, pattern))
            self.assertEqual(shipped, copied, "%s/%s" % (folder, pattern))

    def test_launch_files_resolve(self):
        for path in sorted(glob.glob(os.path.join(self.share, "launch_files", "*.launch"))):
            # Required arguments (no default) get a placeholder: --nodes only resolves the file.
            required = [arg.get("name") for arg in ElementTree.parse(path).getroot().findall("arg")
                        if arg.get("default") is None and arg.get("value") is None]
            result = self.run_installed(["roslaunch", "--nodes", "hidden_rooms", os.path.basename(path)] +
                                        ["%s:=/tmp/placeholder" % name for name in required])
            self.assertEqual(result.returncode, 0, path + "\n" + result.stdout + result.stderr)
            self.assertTrue(result.stdout.strip(), "%s starts no node" % path)

    def test_python_tools_start(self):
        for tool in ("batch_analysis", "plot_batch", "explore_worlds", "make_closed_door_corpus", "carmen_to_bag"):
            result = self.run_installed(["rosrun", "hidden_rooms", tool, "--help"])
            self.assertEqual(result.returncode, 0, tool + "\n" + result.stdout + result.stderr)
            self.assertIn("usage", result.stdout.lower(), tool)

    def mean_iou(self, metrics_path):
        with open(metrics_path) as stream:
            return yaml.safe_load(stream)["mean_iou"]

    def test_demo_prediction_offline(self):
        out = os.path.join(self.folder, "offline")
        self.run_installed(["rosrun", "hidden_rooms", "predict_rooms_offline", "--map",
                            os.path.join(self.case, "map.yaml"), "--doors", os.path.join(self.case, "doors.yaml"),
                            "--method", DEMO_METHOD, "--gt-rooms", os.path.join(self.case, "true_rooms.png"),
                            "--out", out], check=True)
        self.assertGreater(self.mean_iou(os.path.join(out, "metrics.yaml")), 0.5)

    def test_demo_prediction_through_the_service(self):
        port = free_port()
        master = "http://127.0.0.1:%d" % port
        launch = subprocess.Popen(
            ["bash", "-c", SOURCE_AND_RUN, "bash", self.install, "roslaunch", "-p",
             str(port), "hidden_rooms", "predict.launch", "map:=" + os.path.join(self.case, "map.yaml"),
             "doors:=" + os.path.join(self.case, "doors.yaml")],
            env=self.environment(ROS_MASTER_URI=master), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True, start_new_session=True)
        try:
            out = os.path.join(self.folder, "service")
            client = self.run_installed(["rosrun", "hidden_rooms", "predict_rooms_client", "--doors",
                                         os.path.join(self.case, "doors.yaml"), "--gt-rooms",
                                         os.path.join(self.case, "true_rooms.png"), "--out", out, "--timeout", "60"],
                                        timeout=120, ROS_MASTER_URI=master)
            self.assertEqual(client.returncode, 0, client.stdout + client.stderr)
            self.assertGreater(self.mean_iou(os.path.join(out, "metrics.yaml")), 0.5)
        finally:
            os.killpg(launch.pid, signal.SIGINT)
            try:
                launch.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(launch.pid, signal.SIGKILL)
                launch.wait()

    def test_a_downstream_package_builds_against_it(self):
        workspace = os.path.join(self.folder, "downstream_ws")
        os.makedirs(os.path.join(workspace, "src"))
        os.symlink(DOWNSTREAM_PACKAGE, os.path.join(workspace, "src", os.path.basename(DOWNSTREAM_PACKAGE)))
        started = time.monotonic()
        build = self.run_installed(["catkin_make", "-DPYTHON_EXECUTABLE=/usr/bin/python3"], cwd=workspace,
                                   timeout=600)
        self.assertEqual(build.returncode, 0, build.stdout[-4000:] + build.stderr[-4000:])
        print("downstream package built in %.0f s" % (time.monotonic() - started))
        programs = os.path.join(workspace, "devel", "lib", "hidden_rooms_downstream_check")
        predicted = self.run_installed([os.path.join(programs, "predict_with_hidden_rooms"),
                                        os.path.join(self.case, "map.yaml"), os.path.join(self.case, "doors.yaml"),
                                        os.path.join(self.case, "true_rooms.png"), DEMO_METHOD], check=True)
        self.assertIn("rooms 3,", predicted.stdout)
        self.assertGreater(float(predicted.stdout.split("mean_iou")[1]), 0.5)
        messages = self.run_installed([os.path.join(programs, "use_hidden_rooms_messages")], check=True)
        self.assertIn("round trip ok", messages.stdout)


if __name__ == "__main__":
    unittest.main()
