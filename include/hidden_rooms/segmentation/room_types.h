#pragma once

// Room types of a segmented floor, learned from the thesis's labelled floor plans: each room's shape, size, and
// place in the topological map (doors, neighbours) as features, a random forest (OpenCV ml) as classifier. The
// shipped model (models/room_types.yml, built into the library) is trained by train_room_types.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/segmentation/floor.h"

namespace cv::ml {
class RTrees;
}

namespace hidden_rooms::segmentation {

// The types told apart, in class order: corridor, office, classroom, washroom, storage, hall, stairs.
const std::vector<std::string>& roomTypeNames();
// The type of a space labelled `label` in an environment XML (CORRIDOR, OFFICE, CLASSROOM, ...); "" for a label
// of no type.
std::string roomTypeOfLabel(const std::string& label);
// The kind of a space labelled `label`: a corridor when its type is.
RoomKind roomKindOfLabel(const std::string& label);

// One row per room of `floor` (its label order), the columns of roomFeatureNames().
cv::Mat1f roomFeatures(const SegmentedFloor& floor);
const std::vector<std::string>& roomFeatureNames();

class RoomTypeClassifier {
 public:
  // The model of the library (models/room_types.yml).
  static const RoomTypeClassifier& shipped();
  // A model as train_room_types writes it (OpenCV FileStorage text). Throws InputError when it does not read.
  static RoomTypeClassifier fromText(const std::string& model_text, const std::string& source_name);
  // Trains on `features` (roomFeatures rows) with `types` (indices into roomTypeNames()); the forest draws its
  // samples and split features from `seed`, so the same arguments give the same model.
  static RoomTypeClassifier train(const cv::Mat1f& features, const std::vector<int>& types, uint64_t seed = 1);

  // The type index of each row of `features`.
  std::vector<int> classify(const cv::Mat1f& features) const;
  std::string toText() const;

 private:
  explicit RoomTypeClassifier(cv::Ptr<cv::ml::RTrees> forest);
  cv::Ptr<cv::ml::RTrees> forest_;
};

// Sets every room's type and kind (a corridor: type corridor) with `classifier`.
void classifyRooms(const RoomTypeClassifier& classifier, SegmentedFloor* floor);

}  // namespace hidden_rooms::segmentation
