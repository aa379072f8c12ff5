#pragma once

// The thesis's method (docs/method.md#the-thesis-method) behind the RoomPredictor interface: hidden rooms grown cell
// by cell on the layout's cell grid (layout.h), scored by the thesis's utility functions.

#include <map>
#include <string>
#include <vector>

#include "hidden_rooms/common/options.h"
#include "hidden_rooms/prediction/layout.h"
#include "hidden_rooms/prediction/room_predictor.h"

namespace hidden_rooms::prediction {

// The method's constants (config/prediction.yaml documents each one under its `thesis_` name).
struct ThesisOptions {
  // Utility of an independent room: -k1 co - k2 fe - k3 oc + k4 sqrt(ar).
  double ind_k1 = 10.0;
  double ind_k2 = 7.0;
  double ind_k3 = 10.0;
  double ind_k4 = 0.06;
  // Utility of a dependent room: -k1 co - k2 fe - max(k3 (oc - cv), 0) + k4 sqrt(ar) - k5 pr min(oc, 1).
  double dep_k1 = 10.0;
  double dep_k2 = 25.0;
  double dep_k3 = 10.0;
  double dep_k4 = 0.06;
  double dep_k5 = 2.0;
  double dep_cv = 1.0;
  double proportion_threshold = 2.0;   // pr = max(0, long side / short side - threshold)
  int outcast_min_neighbours = 2;      // a room cell with n >= this many free neighbours costs n - (this - 1)
  int depth = 7;                       // greedy expansion steps (level of depth l)
  int max_candidates = 12;             // candidates per expansion step (2^n subsets are scored)
  bool fix_pairs = true;               // exchange cells between adjacent rooms (docs/method.md#pair-fix)
  double fix_k1 = 1.0;                 // pair score: -k1 sqrt(max area / min area) - k2 (co_i + co_j)
  double fix_k2 = 1.0;
  int max_exchangeable = 12;           // exchangeable cells per pair (2^n assignments are scored)
  bool border_rooms = true;            // border-cell rooms grow into squares (docs/method.md#border-rooms)
  bool border_depth_average = false;   // squares growing the same way share their average side as depth
  bool border_cells_free = true;       // OUT border cells count as free in fe and oc
};

// Every ThesisOptions field as a parameter ("thesis_ind_k1", ...) with its range, in config/prediction.yaml's order.
const common::OptionTable<ThesisOptions>& thesisOptionTable();
// Names of every ThesisOptions field as parameters ("thesis_ind_k1", ...), in config/prediction.yaml's order.
const std::vector<std::string>& thesisParameterNames();
std::map<std::string, double> thesisParameters(const ThesisOptions& options);
// Defaults with the `thesis_` entries of `parameters` applied (other names are ignored), validated; throws
// InputError("parameters", "parameter 'x' ...") on a bad value.
ThesisOptions thesisOptionsFromParameters(const std::map<std::string, double>& parameters);

// The score terms of a room made of grid cells (docs/method.md#score-terms). A cell is *free* when it is OUT, not in
// the room and not in `taken` (cells of the other predicted rooms; may be empty = none taken). Adjacency is through
// shared edges.
struct ThesisTerms {
  double co = 0.0;  // (area of the convex hull of the cells' corners - area) / area
  double fe = 0.0;  // free cells adjacent to the room / all cells adjacent to the room
  double oc = 0.0;  // sum over the room's cells with n >= outcast_min_neighbours free neighbours of
                    // n - (outcast_min_neighbours - 1)
  double ar = 0.0;  // area, pixels (whole cell rectangles)
  double pr = 0.0;  // max(0, long / short side of the bounding box - proportion_threshold)
};
ThesisTerms thesisTerms(const CellGrid& grid, const std::vector<int>& cells, const std::vector<bool>& taken,
                        const ThesisOptions& options = ThesisOptions());
// The utility of a room with these terms, independent or dependent.
double thesisScore(const ThesisTerms& terms, bool dependent, const ThesisOptions& options = ThesisOptions());

// The cells predicted for every door start of the layout (same order as layout.doors; empty when the door
// has no start), and per door whether it was a border room, capped, its expansion steps and final status.
struct ThesisRoomCells {
  std::vector<int> cells;
  // The start cell is a border cell: the final room is a square (docs/method.md#border-rooms).
  bool border_room = false;
  cv::Rect square;                // border rooms: the square, image coordinates (empty otherwise)
  bool dependent = false;
  bool candidates_capped = false;
  bool exchangeable_capped = false;
  int steps = 0;                  // expansion steps that changed the room
  int shared_start_with = -1;     // index of an earlier door with the same start cell (copy of its room)
};
std::vector<ThesisRoomCells> thesisRoomCells(const Layout& layout, const ThesisOptions& options = ThesisOptions());

// "thesis": the layout analysis places every door on the cell grid; each hidden room starts from its door's
// OUT cell and grows greedily for `depth` steps: every subset of its candidate cells (OUT, non-border, free,
// sharing an edge or, for independent rooms, a corner with the room) is scored with the room's utility and
// the best replaces the room; then adjacent rooms exchange the cells they touch for similar areas and low
// concavity, and rooms starting on a border cell become squares on the edge they share with the explored
// room. The room is the union of its cells clipped to the cells unknown in the input map.
// terms: co, fe, oc, ar, pr, score, dependent, steps, cells, border_room, candidates_capped,
// exchangeable_capped, start_distance.
class ThesisPredictor : public RoomPredictor {
 public:
  ThesisPredictor() = default;
  std::string name() const override { return "thesis"; }
  std::map<std::string, double> defaultParameters() const override;
  PredictionResult predict(const PredictionRequest& request) const override;
};

}  // namespace hidden_rooms::prediction
