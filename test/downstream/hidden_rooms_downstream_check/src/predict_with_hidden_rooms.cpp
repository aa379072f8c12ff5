// predict_with_hidden_rooms MAP.yaml DOORS.yaml TRUE_ROOMS.png METHOD: predicts the rooms behind the doors with
// the named method and prints the mean IoU against the true rooms ("mean_iou 0.83"). Exit 1 on an error.
#include <cstdio>
#include <exception>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/evaluation/evaluation.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/room_predictor.h"

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: predict_with_hidden_rooms MAP.yaml DOORS.yaml TRUE_ROOMS.png METHOD\n");
    return 2;
  }
  try {
    namespace prediction = hidden_rooms::prediction;
    prediction::PredictionRequest request;
    request.map = hidden_rooms::common::loadMap(argv[1]);
    request.doors = hidden_rooms::common::loadDoors(argv[2]);
    const prediction::PredictionResult result = prediction::makeRoomPredictor(argv[4])->predict(request);
    const cv::Mat1w predicted = prediction::roomLabels(request.map, request.doors, result.rooms);
    const cv::Mat truth = hidden_rooms::common::readImage(argv[3]);
    const auto scores = hidden_rooms::evaluation::scoreRooms(predicted, truth, static_cast<int>(result.rooms.size()));
    std::printf("rooms %zu, predicted cells %d, mean_iou %.3f\n", result.rooms.size(), cv::countNonZero(predicted),
                scores.mean_iou);
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "predict_with_hidden_rooms: %s\n", error.what());
    return 1;
  }
}
