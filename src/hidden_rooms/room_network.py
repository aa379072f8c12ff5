"""The learned room model's input and target windows (docs/method.md#the-learned-room-model).

Mirrors src/prediction/room_network.cpp, which builds the same input at run time: per closed door, a square window
of the map centred on the door's pixel, WINDOW_CELLS cells of WINDOW_CELL_SIZE metres a side, area-averaged from
the map's own pixels (outside the map: unknown), with five channels: occupied, free and unknown share of each
cell, this door's disc and the other closed doors' discs (radius half the door's width). The target is the share
of each cell inside the room behind the door (gt_rooms.png: label k = the k-th door of doors.yaml).
"""
import os

import cv2
import numpy as np
import yaml

WINDOW_CELLS = 96        # cells a side
WINDOW_CELL_SIZE = 0.2   # metres
CHANNELS = ("occupied", "free", "unknown", "door", "other_doors")
# map_server's trinary reading of a map image (negate 0): occupied above occupied_thresh, free below free_thresh.
OCCUPIED, FREE, UNKNOWN = 2, 1, 0


def read_states(map_yaml):
    """(states image: OCCUPIED / FREE / UNKNOWN per pixel, resolution, origin xy) of a map_server map."""
    with open(map_yaml) as stream:
        meta = yaml.safe_load(stream)
    image = cv2.imread(os.path.join(os.path.dirname(map_yaml), meta["image"]), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise ValueError("%s: cannot read its image %s" % (map_yaml, meta["image"]))
    occupancy = (255.0 - image) / 255.0
    states = np.full(image.shape, UNKNOWN, np.uint8)
    states[occupancy < float(meta["free_thresh"])] = FREE
    states[occupancy > float(meta["occupied_thresh"])] = OCCUPIED
    return states, float(meta["resolution"]), (float(meta["origin"][0]), float(meta["origin"][1]))


def read_doors(doors_yaml):
    with open(doors_yaml) as stream:
        return yaml.safe_load(stream)["doors"]


def door_pixel(door, shape, resolution, origin):
    """The image pixel (col, row) of a door's position (OccupancyGrid::toImage, floored)."""
    x = (door["position"][0] - origin[0]) / resolution
    y = shape[0] - (door["position"][1] - origin[1]) / resolution
    return int(np.floor(x)), int(np.floor(y))


def window_pixels(resolution):
    """Side of the window in map pixels."""
    return int(round(WINDOW_CELLS * WINDOW_CELL_SIZE / resolution))


def crop(image, centre, side, fill):
    """The side x side part of `image` whose centre pixel is `centre` (col, row), `fill` outside the image."""
    x0, y0 = centre[0] - side // 2, centre[1] - side // 2
    out = np.full((side, side), fill, image.dtype)
    sx0, sy0 = max(x0, 0), max(y0, 0)
    sx1, sy1 = min(x0 + side, image.shape[1]), min(y0 + side, image.shape[0])
    if sx0 < sx1 and sy0 < sy1:
        out[sy0 - y0:sy1 - y0, sx0 - x0:sx1 - x0] = image[sy0:sy1, sx0:sx1]
    return out


def to_cells(mask):
    """A 0/1 pixel mask as the share of each window cell (area average)."""
    return cv2.resize(mask.astype(np.float32), (WINDOW_CELLS, WINDOW_CELLS), interpolation=cv2.INTER_AREA)


def door_discs(shape, doors, resolution):
    """Mask with a disc per door (pixel, width in metres) of radius half its width."""
    mask = np.zeros(shape, np.uint8)
    for pixel, width in doors:
        cv2.circle(mask, pixel, max(1, int(round(width / 2 / resolution))), 1, -1)
    return mask


def door_window(states, resolution, pixels, widths, index):
    """The model's input for door `index` of the doors at `pixels` (col, row) with `widths` (m): (5, N, N) float32."""
    side = window_pixels(resolution)
    centre = pixels[index]
    window = crop(states, centre, side, UNKNOWN)
    # Door discs in window coordinates (all doors, so discs of doors just outside still reach in).
    offset = (centre[0] - side // 2, centre[1] - side // 2)
    local = [((p[0] - offset[0], p[1] - offset[1]), w) for p, w in zip(pixels, widths)]
    this = door_discs(window.shape, [local[index]], resolution)
    others = door_discs(window.shape, [d for i, d in enumerate(local) if i != index], resolution)
    return np.stack([to_cells(window == OCCUPIED), to_cells(window == FREE), to_cells(window == UNKNOWN),
                     to_cells(this), to_cells(others)])


def read_case(case_dir):
    """(states, resolution, door pixels, door widths, true room labels) of a benchmark case."""
    states, resolution, origin = read_states(os.path.join(case_dir, "map.yaml"))
    doors = read_doors(os.path.join(case_dir, "doors.yaml"))
    truth = cv2.imread(os.path.join(case_dir, "gt_rooms.png"), cv2.IMREAD_UNCHANGED)
    pixels = [door_pixel(d, states.shape, resolution, origin) for d in doors]
    return states, resolution, pixels, [float(d["width"]) for d in doors], truth


def case_windows(states, resolution, pixels, widths, truth):
    """Per closed door: (input window, target window: the share of each cell in its room, label k + 1 of
    `truth` for door k)."""
    side = window_pixels(resolution)
    for i in range(len(pixels)):
        room = crop((truth == i + 1).astype(np.uint8), pixels[i], side, 0)
        yield door_window(states, resolution, pixels, widths, i), to_cells(room)
