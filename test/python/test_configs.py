#!/usr/bin/python3
"""Every shipped config parses: YAML files as YAML, rviz files as rviz's YAML with a Visualization Manager; the
launch files restart what a user wants restarted."""
import glob
import os
import unittest
import xml.etree.ElementTree as ElementTree

import yaml

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))


class ShippedConfigs(unittest.TestCase):
    def test_yaml_configs_load_and_are_commented(self):
        files = sorted(glob.glob(os.path.join(PACKAGE_DIR, "config", "*.yaml")))
        self.assertTrue(files, "no YAML config shipped")
        for path in files:
            with open(path) as stream:
                text = stream.read()
            data = yaml.safe_load(text)
            self.assertIsInstance(data, dict, path)
            self.assertIn("#", text, "%s has no comments" % path)

    def test_rviz_configs_load(self):
        for path in sorted(glob.glob(os.path.join(PACKAGE_DIR, "config", "*.rviz"))):
            with open(path) as stream:
                data = yaml.safe_load(stream)
            self.assertIn("Visualization Manager", data, path)
            self.assertIn("Fixed Frame", data["Visualization Manager"]["Global Options"], path)


# Launch file, node name: how its node handles an end. "respawn": restarted after a delay (stateless, or state it
# rebuilds); "required": its end ends the launch (a restart would silently lose state: the world's clock, the map).
RESTART_POLICY = {
    ("explore.launch", "explorer"): "respawn",
    ("exploration_run.launch", "pose_logger"): "respawn",
    ("view_world.launch", "map_publisher"): "respawn",
    ("predict.launch", "map_publisher"): "respawn",
    ("predict.launch", "room_predictor"): "respawn",
    ("replay.launch", "room_predictor"): "respawn",
    ("simulation.launch", "world_map"): "respawn",
    ("simulation.launch", "simulator"): "required",
    ("mapping.launch", "mapper"): "required",
}


class LaunchFiles(unittest.TestCase):
    def nodes(self, launch_file):
        root = ElementTree.parse(os.path.join(PACKAGE_DIR, "launch_files", launch_file)).getroot()
        return {node.get("name"): node for node in root.iter("node")}

    def test_restart_policy(self):
        for (launch_file, name), policy in sorted(RESTART_POLICY.items()):
            node = self.nodes(launch_file).get(name)
            self.assertIsNotNone(node, "%s has no node %s" % (launch_file, name))
            where = "%s: %s" % (launch_file, name)
            if policy == "respawn":
                self.assertEqual(node.get("respawn"), "true", where)
                self.assertGreater(float(node.get("respawn_delay", "0")), 0.0, where + " needs a respawn_delay")
                self.assertNotEqual(node.get("required"), "true", where)
            else:
                self.assertEqual(node.get("required"), "true", where)
                self.assertNotEqual(node.get("respawn"), "true", where)

    def test_a_respawned_pose_logger_continues_its_logs(self):
        logger = self.nodes("exploration_run.launch")["pose_logger"]
        parameters = {param.get("name"): param.get("value") for param in logger.iter("param")}
        self.assertEqual(parameters.get("append"), "true")


if __name__ == "__main__":
    unittest.main()
