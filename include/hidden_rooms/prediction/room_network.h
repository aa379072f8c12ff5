#pragma once

// The learned room model (docs/method.md#the-learned-room-model): a small convolutional network that reads the map
// around a closed door and scores, per cell, whether it belongs to the room behind that door. Trained on the
// tuning part of the closed-door corpus (scripts/train_room_network, which also states the input and shares its
// window code with src/hidden_rooms/room_network.py); its ONNX file (models/room_network.onnx) is built into the
// library and run by OpenCV's dnn module.
//
// The input per door: a square window of the map centred on the door's pixel, kWindowCells cells of
// kWindowCellSize metres a side, area-averaged from the map's pixels (outside the map: unknown), five channels:
// the occupied, free and unknown share of each cell, this door's disc and the other doors' discs (radius half the
// door's width).

#include <vector>

#include <opencv2/core.hpp>

namespace hidden_rooms::prediction {

constexpr int kWindowCells = 96;          // cells a side of a door's window
constexpr double kWindowCellSize = 0.2;   // metres a cell
constexpr int kWindowChannels = 5;

// A door as the model sees it: its pixel (image frame) and its width in metres.
struct NetworkDoor {
  cv::Point pixel;
  double width = 0.0;
};

// A door's room scores: the log-odds that each cell of its window is the door's room.
struct RoomScores {
  cv::Rect window;   // map pixels, centred on the door (it may reach past the map's edges)
  cv::Mat1f logits;  // kWindowCells square
};

// Side of a door's window in map pixels at `resolution` metres per pixel.
int windowPixels(double resolution);

// Whether the model reads maps of `resolution`: its windows take at most kMaxWindowPixels pixels a side (maps
// finer than about 9.4 mm are not read; their windows would take gigabytes).
constexpr int kMaxWindowPixels = 2048;
bool networkReads(double resolution);

// The model's input for door `index` of `doors` on the working states image `states` (0 unknown, 1 free,
// 2 occupied per pixel): kWindowChannels x kWindowCells x kWindowCells, channel-major, shares in [0, 1].
cv::Mat doorWindowInput(const cv::Mat1b& states, double resolution, const std::vector<NetworkDoor>& doors,
                        size_t index);

// The room scores of every door (batches of kNetworkBatch doors through the network, which bounds memory; safe to
// call from several threads).
constexpr int kNetworkBatch = 16;
std::vector<RoomScores> roomScores(const cv::Mat1b& states, double resolution, const std::vector<NetworkDoor>& doors);

// A door's room as the network sees it: `mask` (255) over the part `box` of the map (image frame) it lies in.
struct NetworkRoom {
  cv::Rect box;
  cv::Mat1b mask;  // box.size()
};

// Per door its room as the network sees it: the unknown pixels of `states` where the door's score (bilinearly
// interpolated from its cells) is the highest of all doors' and gives a probability above `min_probability`
// (in (0, 1)), the parts of them 4-connected to the door's disc grown by `reach` pixels; `box` is the door's window
// within the map. `scores` as roomScores gives them.
std::vector<NetworkRoom> networkRooms(const cv::Mat1b& states, const std::vector<NetworkDoor>& doors,
                                      const std::vector<RoomScores>& scores, double resolution, int reach,
                                      double min_probability);

}  // namespace hidden_rooms::prediction
