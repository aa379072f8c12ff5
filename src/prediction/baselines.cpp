#include "hidden_rooms/prediction/baselines.h"

#include <chrono>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/prediction_support.h"

namespace hidden_rooms::prediction {

namespace {

// Defaults (documented in config/prediction.yaml).
constexpr double kDefaultStartSearchRadius = 1.0;  // m: how far behind the door the first unknown cell may be
constexpr double kDefaultSkewSigma = 2.0;          // m: spread of the density
constexpr double kDefaultSkewPerWidth = 2.0;       // 1/m: shape alpha = c * door width, along the door normal
constexpr double kDefaultSkewThreshold = 0.5;      // density / peak density above which a cell is free

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Runs `predict_one(door, start cell, room)` for every door that has unknown space behind it.
template <typename PredictOne>
PredictionResult predictEveryDoor(const PredictionRequest& request, double start_search_radius,
                                  PredictOne predict_one) {
  const auto start_time = std::chrono::steady_clock::now();
  checkUsableRequest(request);
  PredictionResult result;
  for (const common::MapDoor& door : request.doors.doors) {
    RoomPrediction room;
    room.door_id = door.id;
    room.mask = cv::Mat1b::zeros(request.map.cells.size());
    cv::Point start;
    if (nearestUnknownCell(request.map, door.position, start_search_radius, &start, &room.problem))
      predict_one(door, start, &room);
    finishPrediction(request.map, &room);
    result.rooms.push_back(std::move(room));
  }
  result.seconds = secondsSince(start_time);
  return result;
}

// std::floor as an int without the library call (the hot loop of the ray casting).
inline int floorToInt(double value) {
  const int truncated = static_cast<int>(value);
  return value < truncated ? truncated - 1 : truncated;
}

// Unknown cells connected (4-neighbours) to `start` through unknown cells where `allowed` (given over `window`
// of the map; nothing outside it is allowed) is set. Full-size mask.
cv::Mat1b connectedUnknown(const common::OccupancyGrid& map, const cv::Mat1b& allowed, const cv::Rect& window,
                           cv::Point start) {
  cv::Mat1b result = cv::Mat1b::zeros(map.cells.size());
  if (!window.contains(start)) return result;
  const cv::Mat1b passable = (map.cells(window) == common::OccupancyGrid::kUnknown) & allowed;
  const cv::Point seed = start - window.tl();
  if (passable(seed) == 0) return result;
  cv::Mat1b mask = cv::Mat1b::zeros(window.height + 2, window.width + 2);
  cv::floodFill(passable, mask, seed, 255, nullptr, 0, 0, 4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
  mask(cv::Rect(1, 1, window.width, window.height)).copyTo(result(window));
  return result;
}

}  // namespace

std::map<std::string, double> UnstructuredPredictor::defaultParameters() const {
  return {{"start_search_radius", kDefaultStartSearchRadius}};
}

PredictionResult UnstructuredPredictor::predict(const PredictionRequest& request) const {
  const double radius = resolveParameters(*this, request.parameters).at("start_search_radius");
  checkUsableRequest(request);
  const cv::Rect box = knownBoundingBox(request.map);
  return predictEveryDoor(request, radius, [&](const common::MapDoor&, cv::Point start, RoomPrediction* room) {
    // Rays from the centre of the start cell, half a cell apart at the farthest corner of the box.
    const cv::Point2d origin(start.x + 0.5, start.y + 0.5);
    const double reach = std::hypot(std::max(origin.x - box.x, box.br().x - origin.x),
                                    std::max(origin.y - box.y, box.br().y - origin.y));
    const int rays = std::max(360, static_cast<int>(std::ceil(2.0 * CV_PI * reach / 0.5)));
    for (int i = 0; i < rays; ++i) {
      const double angle = 2.0 * CV_PI * i / rays;
      const cv::Point2d step(0.5 * std::cos(angle), 0.5 * std::sin(angle));
      for (cv::Point2d p = origin;; p += step) {
        const cv::Point cell(floorToInt(p.x), floorToInt(p.y));
        if (!box.contains(cell) || request.map.cells(cell) != common::OccupancyGrid::kUnknown) break;
        room->mask(cell) = 255;
      }
    }
    room->terms["rays"] = rays;
  });
}

std::map<std::string, double> SkewNormalPredictor::defaultParameters() const {
  return {{"start_search_radius", kDefaultStartSearchRadius},
          {"skewnormal_sigma", kDefaultSkewSigma},
          {"skewnormal_shape_per_width", kDefaultSkewPerWidth},
          {"skewnormal_p_th", kDefaultSkewThreshold}};
}

PredictionResult SkewNormalPredictor::predict(const PredictionRequest& request) const {
  const auto parameters = resolveParameters(*this, request.parameters);
  const double radius = parameters.at("start_search_radius");
  const double sigma = parameters.at("skewnormal_sigma");
  const double shape_per_width = parameters.at("skewnormal_shape_per_width");
  const double threshold = parameters.at("skewnormal_p_th");
  if (sigma <= 0.0) throw common::InputError("parameters", "skewnormal_sigma must be positive");
  if (threshold <= 0.0 || threshold >= 1.0) throw common::InputError("parameters", "skewnormal_p_th must be in (0, 1)");
  const common::OccupancyGrid& map = request.map;

  return predictEveryDoor(request, radius, [&](const common::MapDoor& door, cv::Point start, RoomPrediction* room) {
    // Normal of the door line, pointing to the side of the start cell (the unknown side).
    common::Point2 normal =
        door.orientation == common::DoorOrientation::kAlongX ? common::Point2(0, 1) : common::Point2(1, 0);
    if ((map.cellCentre(start.x, start.y) - door.position).dot(normal) < 0) normal = -normal;
    const double alpha = shape_per_width * door.width;
    // Density 2 phi(u) Phi(alpha u_n / sigma) in the door frame, evaluated within 4 sigma. The door's axes are
    // the map's, so it separates into a factor per column and one per row.
    const int half = static_cast<int>(std::ceil(4.0 * sigma / map.resolution));
    int col = 0, row = 0;
    map.cellOf(door.position, &col, &row);
    const cv::Rect window = cv::Rect(col - half, row - half, 2 * half + 1, 2 * half + 1) &
                            cv::Rect(0, 0, map.width(), map.height());
    if (window.area() == 0) return;  // the door lies farther than 4 sigma outside the map: nothing likely
    auto factor = [&](double offset, double normal_component) {  // offset: metres from the door along an axis
      const double t = offset / sigma;
      return normal_component != 0.0
                 ? std::exp(-0.5 * t * t) * std::erfc(-alpha * normal_component * t / std::sqrt(2.0))
                 : std::exp(-0.5 * t * t);
    };
    cv::Mat1f column_factor(1, window.width), row_factor(window.height, 1);
    for (int c = 0; c < window.width; ++c)
      column_factor(0, c) = static_cast<float>(
          factor(map.cellCentre(window.x + c, 0).x() - door.position.x(), normal.x()));
    for (int r = 0; r < window.height; ++r)
      row_factor(r, 0) = static_cast<float>(
          factor(map.cellCentre(0, window.y + r).y() - door.position.y(), normal.y()));
    const cv::Mat1f values = row_factor * column_factor;  // proportional to the density over the window
    double peak = 0.0;
    cv::minMaxLoc(values, nullptr, &peak);
    room->mask = connectedUnknown(map, values > threshold * peak, window, start);
    room->terms["alpha"] = alpha;
  });
}

}  // namespace hidden_rooms::prediction
