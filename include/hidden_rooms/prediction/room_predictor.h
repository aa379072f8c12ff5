#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"

namespace hidden_rooms::prediction {

// What every prediction method gets: the explored map and its closed doors (map frame), plus optional
// parameter overrides (`name: value` pairs from a parameters file or a service request) and an optional folder
// for per-stage debug images (empty = none).
struct PredictionRequest {
  common::OccupancyGrid map;
  common::DoorsFile doors;
  std::map<std::string, double> parameters;
  std::string debug_dir;
};

// The prediction for one closed door. `mask` has the map's size: 255 on the free interior cells predicted for
// this door's room (always cells unknown in the input map), 0 elsewhere.
struct RoomPrediction {
  int door_id = 0;
  bool placed = false;
  std::string problem;                  // why the door could not be placed, when !placed
  cv::Mat1b mask;
  common::Polygon polygon;              // outline of the room, map frame, metres (empty when !placed)
  double area = 0.0;                    // square metres of mask
  std::map<std::string, double> terms;  // the method's score terms, for reports
};

struct PredictionResult {
  std::vector<RoomPrediction> rooms;  // one per door of the request, same order
  double seconds = 0.0;               // computation time
};

// One interface for the prediction method and its baselines, chosen by name (`makeRoomPredictor`).
class RoomPredictor {
 public:
  virtual ~RoomPredictor() = default;
  virtual std::string name() const = 0;
  // Every parameter the method reads, with its default (config/prediction.yaml and config/layout.yaml
  // document them).
  virtual std::map<std::string, double> defaultParameters() const = 0;
  // Predicts a room behind every door. A door that cannot be placed (outside the map, no unknown space behind
  // it) gets placed = false and a problem; the others are still predicted. Throws InputError only for
  // a request that is unusable as a whole (empty map, unknown parameter name, bad parameter value).
  virtual PredictionResult predict(const PredictionRequest& request) const = 0;
};

// The method's defaults with the overrides applied. Overrides of parameters that only other registered methods
// read are ignored (one parameters file serves every method); a name no method reads, or a non-finite value,
// throws InputError("parameters", ...).
std::map<std::string, double> resolveParameters(const RoomPredictor& method,
                                                const std::map<std::string, double>& overrides);

// The registered methods, e.g. {"skewnormal", "structured", "unstructured"}.
std::vector<std::string> roomPredictorNames();
// Throws InputError naming the method and the known ones when `name` is not registered.
std::unique_ptr<RoomPredictor> makeRoomPredictor(const std::string& name);

}  // namespace hidden_rooms::prediction
