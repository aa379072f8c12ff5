#pragma once

// The thesis's unstructured baseline (docs/method.md#baselines) and the skew-normal door extrapolation of the
// related work (seed 001), behind the RoomPredictor interface. The structured baseline is in structured_predictor.h.

#include <string>
#include <vector>

#include "hidden_rooms/prediction/room_predictor.h"

namespace hidden_rooms::prediction {

// "unstructured": from the unknown cell nearest the door, every unknown cell seen along a straight line
// through unknown cells (a 360° laser from that cell), stopped by known cells and the known cells' bounding box.
class UnstructuredPredictor : public RoomPredictor {
 public:
  std::string name() const override { return "unstructured"; }
  std::map<std::string, double> defaultParameters() const override;
  PredictionResult predict(const PredictionRequest& request) const override;
};

// "skewnormal": free space extrapolated behind the door with a bivariate skew-normal density centred on the
// door, skewed into the unknown side in proportion to the door width; free where the density, normalised to
// its peak, exceeds p_th; clipped to the unknown cells connected to the door.
class SkewNormalPredictor : public RoomPredictor {
 public:
  std::string name() const override { return "skewnormal"; }
  std::map<std::string, double> defaultParameters() const override;
  PredictionResult predict(const PredictionRequest& request) const override;
};

}  // namespace hidden_rooms::prediction
