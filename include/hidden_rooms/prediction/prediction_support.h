#pragma once

// Pieces shared by the prediction methods.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/prediction/room_predictor.h"

namespace hidden_rooms::prediction {

// Smallest rectangle holding every known (free or occupied) cell; empty when the map has none.
cv::Rect knownBoundingBox(const common::OccupancyGrid& map);

// The unknown cell nearest to `position` within `max_distance` metres (the first cell behind a closed door).
// False when the position is outside the map or no unknown cell is that close; `problem` then says which.
bool nearestUnknownCell(const common::OccupancyGrid& map, const common::Point2& position, double max_distance,
                        cv::Point* cell, std::string* problem);

// Fills polygon (outer contour of the largest blob, map frame) and area (m²) of a prediction from its mask,
// and sets placed = true; an empty mask makes it not placed with `problem` "no room predicted". When the caller
// knows a rectangle holding every cell of the mask, `cells_within` spares the scan of the whole image.
void finishPrediction(const common::OccupancyGrid& map, RoomPrediction* room,
                      const std::optional<cv::Rect>& cells_within = std::nullopt);

// The prediction of a door that could not be placed: empty mask of the map's size, placed = false, `problem`.
RoomPrediction unplacedRoom(const common::OccupancyGrid& map, int door_id, const std::string& problem);

// Throws InputError when the map has no cells, no known cell or no free cell.
void checkUsableMap(const common::OccupancyGrid& map);

// Every method's first check: a usable map, and the map's cells, the doors and their product within the limits
// of common/input_limits.h. Throws InputError naming the limit.
void checkUsableRequest(const PredictionRequest& request);

// The input map completed with the predicted rooms (docs/method.md#completed-map): each placed room's cells free,
// unknown cells around it walled, and its door opened as a free rectangle of the door's width joining the room to the
// explored side.
common::OccupancyGrid insertRooms(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                                  const std::vector<RoomPrediction>& rooms);

// Label image of the map's size: k on the cells of the room predicted for the k-th door (1-based), 0 elsewhere;
// 16-bit so that more than 255 doors fit. A cell claimed by several rooms goes to the one whose door is nearest.
cv::Mat1w roomLabels(const common::OccupancyGrid& map, const common::DoorsFile& doors,
                     const std::vector<RoomPrediction>& rooms);

// Picture for people: the map in grey, each predicted room tinted in its own colour and, when `true_labels` is
// not empty (same labels), each true room outlined in green.
cv::Mat3b renderPredictionOverlay(const common::OccupancyGrid& map, const cv::Mat1w& predicted_labels,
                                  const cv::Mat& true_labels);

}  // namespace hidden_rooms::prediction
