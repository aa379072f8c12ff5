#!/usr/bin/python3
"""Every shipped config parses: YAML files as YAML, rviz files as rviz's YAML with a Visualization Manager."""
import glob
import os
import unittest

import yaml

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))


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


if __name__ == "__main__":
    unittest.main()
