#!/usr/bin/python3
"""hidden_rooms.room_network (the learned room model's windows, as scripts/train_room_network reads them): the
same facts on the same map as test/prediction/test_room_network.cpp states of the C++ windows the package builds at
run time, read from a case in the benchmark's layout."""
import os
import sys
import tempfile
import unittest

import cv2
import numpy as np

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
sys.path.insert(0, os.path.join(PACKAGE_DIR, "src"))
from hidden_rooms import room_network  # noqa: E402


def write_case(folder):
    """A 10 m x 6 m map at 5 cm: a free corridor 1 m high along the bottom, its upper wall at row 99, the rest
    unknown; doors at columns 100 and 160 of that wall, the room behind the first 4 m wide and 3 m deep."""
    image = np.full((120, 200), 205, np.uint8)
    image[100:120, :] = 254
    image[99, :] = 0
    cv2.imwrite(os.path.join(folder, "map.pgm"), image)
    with open(os.path.join(folder, "map.yaml"), "w") as stream:
        stream.write("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    with open(os.path.join(folder, "doors.yaml"), "w") as stream:
        stream.write("frame: map\ndoors:\n")
        for door_id, column in ((1, 100), (2, 160)):
            # Pixel (column, 99) of the 120-row map: y = (120 - 99.5) * 0.05.
            stream.write("  - id: %d\n    position: [%.3f, %.3f]\n    width: 1.0\n    orientation: O\n"
                         % (door_id, (column + 0.5) * 0.05, (120 - 99.5) * 0.05))
    truth = np.zeros((120, 200), np.uint8)
    truth[39:99, 60:140] = 1
    cv2.imwrite(os.path.join(folder, "gt_rooms.png"), truth)


class RoomNetworkWindows(unittest.TestCase):
    def test_windows_mirror_the_run_time_ones(self):
        with tempfile.TemporaryDirectory() as folder:
            write_case(folder)
            states, resolution, pixels, widths, truth = room_network.read_case(folder)
            self.assertEqual(pixels, [(100, 99), (160, 99)])
            self.assertEqual(room_network.window_pixels(resolution), 384)
            windows = list(room_network.case_windows(states, resolution, pixels, widths, truth))
        self.assertEqual(len(windows), 2)
        window, room = windows[0]
        self.assertEqual(window.shape, (5, 96, 96))
        shares = window[0] + window[1] + window[2]
        self.assertTrue(np.allclose(shares, 1.0, atol=1e-5))
        # As the C++ test: free corridor below the door, unknown beyond the map, the door's disc at the centre,
        # the other door's 3 m to the right.
        self.assertEqual(window[1, 50, 48], 1.0)
        self.assertEqual(window[2, 60, 48], 1.0)
        self.assertEqual(window[2, 40, 48], 1.0)
        self.assertGreater(window[3, 48, 48], 0.9)
        self.assertEqual(window[3, 48, 63], 0.0)
        self.assertGreater(window[4, 48, 63], 0.9)
        self.assertEqual(window[4, 48, 48], 0.0)
        # The target: the room's 4 m x 3 m (20 x 15 cells) above the door, nothing for the second door.
        self.assertAlmostEqual(float(room.sum()), 20 * 15, delta=1.0)
        self.assertEqual(float(room[34:47, 39:57].min()), 1.0)
        self.assertEqual(float(windows[1][1].sum()), 0.0)


if __name__ == "__main__":
    unittest.main()
