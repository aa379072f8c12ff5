#!/usr/bin/python3
"""package.xml's dependencies resolve with rosdep on Debian 12: its system keys are exactly those of rosdep.yaml,
and rosdep itself (python3-rosdep2, without the network: Debian's list of ROS packages and rosdep.yaml as its only
sources) resolves every key to installed Debian packages."""
import os
import shutil
import subprocess
import tempfile
import unittest

import yaml
from catkin_pkg.package import parse_package

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
DEBIAN_ROS_LIST = "/usr/share/python3-rosdep2/debian.yaml"  # Debian's rosdep source for ROS packages


def package_keys():
    package = parse_package(PACKAGE_DIR)
    dependencies = (package.buildtool_depends + package.build_depends + package.build_export_depends +
                    package.exec_depends + package.test_depends)
    return {dependency.name for dependency in dependencies}


class RosdepKeys(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if not os.path.isfile(DEBIAN_ROS_LIST):
            raise AssertionError("%s missing: python3-rosdep2 is not installed (scripts/setup.sh installs it)"
                                 % DEBIAN_ROS_LIST)
        with open(DEBIAN_ROS_LIST) as stream:
            cls.ros_keys = set(yaml.safe_load(stream))
        with open(os.path.join(PACKAGE_DIR, "rosdep.yaml")) as stream:
            cls.system_entries = yaml.safe_load(stream)

    def test_system_keys_are_those_of_rosdep_yaml(self):
        keys = package_keys()
        self.assertEqual(keys - self.ros_keys, set(self.system_entries),
                         "package.xml's keys that are not ROS packages and rosdep.yaml's keys differ")
        for key, entry in self.system_entries.items():
            self.assertEqual(set(entry), {"debian"}, key)
            self.assertTrue(entry["debian"] and all(isinstance(name, str) for name in entry["debian"]), key)

    def test_rosdep_resolves_every_key_to_installed_packages(self):
        home = tempfile.mkdtemp(prefix="rosdep_test_")
        self.addCleanup(shutil.rmtree, home)
        sources = os.path.join(home, "sources.list.d")
        os.makedirs(sources)
        with open(os.path.join(sources, "20-hidden-rooms.list"), "w") as stream:
            stream.write("yaml file://%s debian\nyaml file://%s/rosdep.yaml\n" % (DEBIAN_ROS_LIST, PACKAGE_DIR))
        with open(os.path.join(home, "index.yaml"), "w") as stream:
            stream.write("%YAML 1.1\n---\ntype: index\nversion: 4\ndistributions: {}\n")
        # rosdep crawls --from-paths for package.xml files: a folder with only this one.
        crawled = os.path.join(home, "package")
        os.makedirs(crawled)
        os.symlink(os.path.join(PACKAGE_DIR, "package.xml"), os.path.join(crawled, "package.xml"))
        env = dict(os.environ, ROSDEP_SOURCE_PATH=sources, ROS_HOME=home,
                   ROSDISTRO_INDEX_URL="file://%s/index.yaml" % home)
        update = subprocess.run(["rosdep", "update"], env=env, capture_output=True, text=True, timeout=120)
        self.assertEqual(update.returncode, 0, update.stdout + update.stderr)
        check = subprocess.run(["rosdep", "check", "--from-paths", crawled, "--ignore-src"], env=env,
                               capture_output=True, text=True, timeout=120)
        self.assertEqual(check.returncode, 0, check.stdout + check.stderr)
        self.assertIn("All system dependencies have been satisfied", check.stdout)


if __name__ == "__main__":
    unittest.main()
