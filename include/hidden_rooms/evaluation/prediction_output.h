#pragma once

// The files a prediction is saved as, written by predict_rooms_offline and predict_rooms_client alike:
//   DIR/rooms.png     label image of the map's size: k on the cells of the room of the k-th door (16-bit over 255)
//   DIR/rooms.yaml    per door: door_id, label, placed (+ problem), area (m²), polygon (map frame), terms
//   DIR/map.yaml/pgm  the input map completed with the rooms (insertRooms)
//   DIR/overlay.png   picture: predicted rooms tinted, true rooms outlined in green
//   DIR/metrics.yaml  only with true rooms: IoU per door, mean IoU, IoU_tot

#include <iosfwd>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/evaluation/evaluation.h"
#include "hidden_rooms/prediction/room_predictor.h"

namespace hidden_rooms::evaluation {

struct PredictionOutputs {
  cv::Mat1w labels;                 // what rooms.png holds
  std::optional<RoomScores> scores;  // set when true rooms were given
};

// Writes the files above into `out` and commits them (all or nothing). `true_labels` (same size as the map, same
// labels) is optional. Throws InputError naming a file that cannot be written or would replace an input.
PredictionOutputs writePredictionOutputs(const prediction::PredictionRequest& request,
                                         const prediction::PredictionResult& result, const std::string& method,
                                         common::OutputFolder* out, const cv::Mat& true_labels = cv::Mat());

// Reads a true rooms label image and checks it has the map's size; throws InputError naming the file.
cv::Mat loadTrueRooms(const std::string& path, const common::OccupancyGrid& map);

// The summary the tools print: "METHOD: N doors in S s -> DIR", the doors not placed and, with scores, the
// IoU per door and the means.
void printPredictionSummary(std::ostream& out, const prediction::PredictionRequest& request,
                            const prediction::PredictionResult& result, const std::string& method,
                            const std::string& out_dir, const PredictionOutputs& outputs);

}  // namespace hidden_rooms::evaluation
