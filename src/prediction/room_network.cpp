#include "hidden_rooms/prediction/room_network.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/embedded_file.h"

// The ONNX file, built into the library (CMake sets HIDDEN_ROOMS_ROOM_NETWORK_ONNX to its path).
HIDDEN_ROOMS_EMBED_FILE(hidden_rooms_room_network_onnx, HIDDEN_ROOMS_ROOM_NETWORK_ONNX);

namespace hidden_rooms::prediction {
namespace {

constexpr uint8_t kUnknownState = 0, kFreeState = 1, kOccupiedState = 2;

// Rounding as the training code's (Python's round: halves to even), so that both draw the same windows.
int roundHalfEven(double value) { return static_cast<int>(std::nearbyint(value)); }

// Radius in pixels of a door's disc: half its width (`width` metres), at least one pixel.
int discRadius(double width, double resolution) { return std::max(1, roundHalfEven(width / 2.0 / resolution)); }

// A 0/255 mask as the share of each window cell.
cv::Mat1f toCells(const cv::Mat1b& mask) {
  cv::Mat1f shares;
  mask.convertTo(shares, CV_32F, 1.0 / 255.0);
  cv::resize(shares, shares, cv::Size(kWindowCells, kWindowCells), 0, 0, cv::INTER_AREA);
  return shares;
}

// The network, read once; cv::dnn::Net runs one forward pass at a time.
struct LoadedNetwork {
  std::mutex mutex;
  cv::dnn::Net net = cv::dnn::readNetFromONNX(hidden_rooms_room_network_onnx,
                                              hidden_rooms_room_network_onnx_end - hidden_rooms_room_network_onnx);
};

LoadedNetwork& loadedNetwork() {
  static LoadedNetwork network;
  return network;
}

// The window of a door centred on `pixel`, in map pixels.
cv::Rect windowAround(const cv::Point& pixel, int side) { return {pixel.x - side / 2, pixel.y - side / 2, side, side}; }

}  // namespace

int windowPixels(double resolution) {
  return static_cast<int>(std::clamp(std::nearbyint(kWindowCells * kWindowCellSize / resolution), 1.0, 1e9));
}

bool networkReads(double resolution) { return windowPixels(resolution) <= kMaxWindowPixels; }

cv::Mat doorWindowInput(const cv::Mat1b& states, double resolution, const std::vector<NetworkDoor>& doors,
                        size_t index) {
  const int side = windowPixels(resolution);
  const cv::Rect window = windowAround(doors[index].pixel, side);
  cv::Mat1b part(side, side, kUnknownState);
  const cv::Rect inside = window & cv::Rect(0, 0, states.cols, states.rows);
  if (inside.area() > 0) states(inside).copyTo(part(inside - window.tl()));

  cv::Mat1b this_door = cv::Mat1b::zeros(side, side), other_doors = cv::Mat1b::zeros(side, side);
  for (size_t i = 0; i < doors.size(); ++i) {
    const int radius = discRadius(doors[i].width, resolution);
    const cv::Point centre = doors[i].pixel - window.tl();
    if (std::abs(centre.x - side / 2) > side + radius || std::abs(centre.y - side / 2) > side + radius) continue;
    cv::circle(i == index ? this_door : other_doors, centre, radius, 255, cv::FILLED);
  }
  const cv::Mat1f channels[kWindowChannels] = {toCells(part == kOccupiedState), toCells(part == kFreeState),
                                               toCells(part == kUnknownState), toCells(this_door),
                                               toCells(other_doors)};
  const int sizes[] = {kWindowChannels, kWindowCells, kWindowCells};
  cv::Mat input(3, sizes, CV_32F);
  for (int c = 0; c < kWindowChannels; ++c)
    channels[c].copyTo(cv::Mat(kWindowCells, kWindowCells, CV_32F, input.ptr<float>(c)));
  return input;
}

std::vector<RoomScores> roomScores(const cv::Mat1b& states, double resolution, const std::vector<NetworkDoor>& doors) {
  const int side = windowPixels(resolution);
  const size_t per_door = static_cast<size_t>(kWindowChannels) * kWindowCells * kWindowCells;
  const size_t per_output = static_cast<size_t>(kWindowCells) * kWindowCells;
  std::vector<RoomScores> scores(doors.size());
  for (size_t first = 0; first < doors.size(); first += kNetworkBatch) {
    const int count = static_cast<int>(std::min<size_t>(kNetworkBatch, doors.size() - first));
    const int sizes[] = {count, kWindowChannels, kWindowCells, kWindowCells};
    cv::Mat batch(4, sizes, CV_32F);
    for (int k = 0; k < count; ++k) {
      const cv::Mat input = doorWindowInput(states, resolution, doors, first + k);
      std::copy_n(input.ptr<float>(), per_door, batch.ptr<float>() + k * per_door);
    }
    cv::Mat output;
    {
      LoadedNetwork& network = loadedNetwork();
      const std::lock_guard<std::mutex> lock(network.mutex);
      network.net.setInput(batch);
      output = network.net.forward().clone();
    }
    for (int k = 0; k < count; ++k) {
      RoomScores& door = scores[first + k];
      door.window = windowAround(doors[first + k].pixel, side);
      door.logits = cv::Mat1f(kWindowCells, kWindowCells, output.ptr<float>() + k * per_output).clone();
    }
  }
  return scores;
}

std::vector<NetworkRoom> networkRooms(const cv::Mat1b& states, const std::vector<NetworkDoor>& doors,
                                      const std::vector<RoomScores>& scores, double resolution, int reach,
                                      double min_probability) {
  const cv::Rect image(0, 0, states.cols, states.rows);
  // Per pixel of the union of the windows, the highest score above min_probability's log-odds and its door
  // (1-based).
  cv::Rect all;
  for (const RoomScores& door : scores) all |= door.window & image;
  cv::Mat1f best(all.size(), static_cast<float>(std::log(min_probability / (1.0 - min_probability))));
  cv::Mat1i owner(all.size(), 0);
  for (size_t i = 0; i < scores.size(); ++i) {
    const cv::Rect inside = scores[i].window & image;
    if (inside.area() == 0) continue;
    cv::Mat1f window_logits;
    cv::resize(scores[i].logits, window_logits, scores[i].window.size(), 0, 0, cv::INTER_LINEAR);
    const cv::Mat1f logits = window_logits(inside - scores[i].window.tl());
    cv::Mat1f best_part = best(inside - all.tl());
    cv::Mat1i owner_part = owner(inside - all.tl());
    const cv::Mat1b higher = logits > best_part;
    logits.copyTo(best_part, higher);
    owner_part.setTo(static_cast<int>(i) + 1, higher);
  }
  if (all.area() > 0) owner.setTo(0, states(all) != kUnknownState);

  std::vector<NetworkRoom> rooms(doors.size());
  for (size_t i = 0; i < doors.size(); ++i) {
    NetworkRoom& room = rooms[i];
    room.box = scores[i].window & image;
    room.mask = cv::Mat1b::zeros(room.box.size());
    if (room.box.area() == 0) continue;
    const cv::Mat1b candidate = owner(room.box - all.tl()) == static_cast<int>(i) + 1;
    cv::Mat1i components;
    const int count = cv::connectedComponents(candidate, components, 4, CV_32S);
    cv::Mat1b disc = cv::Mat1b::zeros(room.box.size());
    const int radius = discRadius(doors[i].width, resolution) + reach;
    cv::circle(disc, doors[i].pixel - room.box.tl(), radius, 255, cv::FILLED);
    std::vector<bool> touching(count, false);
    for (int y = 0; y < disc.rows; ++y)
      for (int x = 0; x < disc.cols; ++x)
        if (disc(y, x) && components(y, x) > 0) touching[components(y, x)] = true;
    for (int y = 0; y < room.mask.rows; ++y)
      for (int x = 0; x < room.mask.cols; ++x) room.mask(y, x) = touching[components(y, x)] ? 255 : 0;
  }
  return rooms;
}

}  // namespace hidden_rooms::prediction
