#include "hidden_rooms/segmentation/floor.h"

namespace hidden_rooms::segmentation {

const char* toString(RoomKind kind) { return kind == RoomKind::kCorridor ? "corridor" : "room"; }

const char* toString(PassageKind kind) {
  switch (kind) {
    case PassageKind::kOpen: return "open";
    case PassageKind::kClosed: return "closed";
    case PassageKind::kPredicted: return "predicted";
  }
  return "open";
}

}  // namespace hidden_rooms::segmentation
