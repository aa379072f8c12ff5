#pragma once

// Internal to the thesis method (thesis_predictor.h): the rooms grown on the layout's cell grid, their greedy
// expansion (docs/method.md#growing-a-room), the pair fix (docs/method.md#pair-fix) and the first stage of the
// border rooms (docs/method.md#border-rooms). thesisTerms and thesisScore are defined with them.

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/prediction/layout.h"
#include "hidden_rooms/prediction/thesis_predictor.h"

namespace hidden_rooms::prediction {

// A hidden room being grown: its door (index into Layout::doors), start cell (OUT) and explored cell (IN), its
// cells, and what the growth reports about it.
struct ThesisRoom {
  int door = -1;
  int start = -1;
  int explored = -1;
  std::vector<int> cells;
  bool dependent = false;        // at its last expansion step
  bool capped = false;           // an expansion step kept only options.max_candidates candidates
  bool exchange_capped = false;  // a pair fix kept only options.max_exchangeable cells
  bool settled = false;          // its last step changed nothing, and no room has grown near it since
  int steps = 0;                 // expansion steps that changed it
};

// The rooms of one layout, each cell owned by at most one room. `layout` and `options` must outlive it.
class ThesisExpansion {
 public:
  ThesisExpansion(const Layout& layout, const ThesisOptions& options);

  // Adds a room of the one cell `start` (not owned yet); returns its index.
  int addRoom(int door, int start, int explored);
  // Up to options.depth rounds of one expansion step per unsettled room, in index order; ends early after a
  // round that changed no room.
  void expand();
  // The pair fix of every pair of adjacent rooms, in index order.
  void fixPairs();
  // Border rooms' first stage: room r takes, until none is left, every free OUT cell sharing an edge with it that
  // shares an edge with an IN cell of `explored_room`.
  void growBorderRoom(int r, int explored_room);
  // Whether a cell of room r shares an edge with a cell of another room.
  bool isDependent(int r) const;

  std::vector<ThesisRoom>& rooms() { return rooms_; }

 private:
  struct Candidates;
  struct SubsetParts;

  // OUT, not owned and (unless options.border_cells_free) not a border cell.
  bool isFree(int c) const;
  bool adjacent(int a, int b) const;
  // Unsettles every settled room other than `changed_room` with a cell within two grid cells of an added one.
  void unsettleNear(const std::vector<int>& added, int changed_room);

  // One expansion step of room r (docs/method.md#growing-a-room): adds the best subset of its candidates and
  // returns the added cells (empty when the room stays as it is).
  std::vector<int> expandOnce(int r);
  Candidates findCandidates(const ThesisRoom& room);
  void capCandidates(ThesisRoom* room, Candidates* candidates) const;
  SubsetParts subsetParts(const ThesisRoom& room, const std::vector<int>& candidates);
  void addRoomShape(const ThesisRoom& room, SubsetParts* parts) const;
  void addAdjacentCells(const ThesisRoom& room, int in_room, int in_adjacent, SubsetParts* parts);
  void addOutcasts(const ThesisRoom& room, SubsetParts* parts) const;
  void addCandidateParts(int in_room, int in_adjacent, SubsetParts* parts) const;
  bool connectedToRoom(uint32_t subset, const SubsetParts& parts) const;
  ThesisTerms subsetTerms(uint32_t subset, const SubsetParts& parts, std::vector<cv::Point>* points,
                          std::vector<cv::Point>* hull);
  uint32_t bestSubset(const SubsetParts& parts, bool dependent);

  // The pair fix of rooms a and b (docs/method.md#pair-fix).
  void fixPair(int a, int b);
  std::vector<int> exchangeableCells(int a, int b);

  const CellGrid& grid_;
  const ThesisOptions& options_;
  std::vector<std::array<int, 4>> neighbours_;  // edge neighbours of every cell, -1 where the grid ends
  std::vector<int> owner_;                      // room of every cell, -1 for none
  std::vector<int> mark_;                       // scratch marks, compared with fresh stamps
  std::vector<int> local_;                      // candidate index of every cell during a step, -1 otherwise
  int stamp_ = 0;
  std::vector<ThesisRoom> rooms_;
};

}  // namespace hidden_rooms::prediction
