#include "hidden_rooms/prediction/thesis_predictor.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/structured_predictor.h"
#include "hidden_rooms/prediction/thesis_expansion.h"

namespace hidden_rooms::prediction {

namespace {

void validate(const ThesisOptions& o) { common::validateOptions(thesisOptionTable(), o, "parameter "); }

enum class Growth { kUp, kDown, kLeft, kRight };

// Border rooms (docs/method.md#border-rooms), second stage for one border room: the extent of its contact with the
// explored room along the door's wall, and the direction away from the explored room.
struct BorderSide {
  Growth growth = Growth::kDown;
  int line = 0;       // the door's wall line (y for up/down, x for left/right), image coordinates
  int low = 0, high = 0;  // contact extent along the wall
};

bool borderSide(const CellGrid& grid, const DoorStart& start, const std::vector<int>& cells, BorderSide* side) {
  const cv::Rect& out = grid.cells[start.start_cell].rect;
  const cv::Rect& in = grid.cells[start.explored_cell].rect;
  const int explored_room = grid.cells[start.explored_cell].room;
  const bool horizontal_edge = start.edge.a.y() == start.edge.b.y();
  if (horizontal_edge) {
    side->growth = in.y < out.y ? Growth::kDown : Growth::kUp;
    side->line = static_cast<int>(std::lround(start.edge.a.y()));
  } else {
    side->growth = in.x < out.x ? Growth::kRight : Growth::kLeft;
    side->line = static_cast<int>(std::lround(start.edge.a.x()));
  }
  int low = std::numeric_limits<int>::max(), high = std::numeric_limits<int>::min();
  for (int c : cells) {
    const int i = grid.column(c), j = grid.row(c);
    int ni = i, nj = j;
    switch (side->growth) {
      case Growth::kDown: nj = j - 1; break;
      case Growth::kUp: nj = j + 1; break;
      case Growth::kRight: ni = i - 1; break;
      case Growth::kLeft: ni = i + 1; break;
    }
    if (ni < 0 || nj < 0 || ni >= grid.columns() || nj >= grid.rows()) continue;
    const LayoutCell& nb = grid.cells[grid.index(ni, nj)];
    if (nb.out || nb.room != explored_room) continue;
    const cv::Rect& r = grid.cells[c].rect;
    if (horizontal_edge) {
      low = std::min(low, r.x);
      high = std::max(high, r.x + r.width);
    } else {
      low = std::min(low, r.y);
      high = std::max(high, r.y + r.height);
    }
  }
  if (high <= low) return false;
  side->low = low;
  side->high = high;
  return true;
}

cv::Rect squareRect(const BorderSide& side, int depth) {
  const int length = side.high - side.low;
  switch (side.growth) {
    case Growth::kDown: return cv::Rect(side.low, side.line, length, depth);
    case Growth::kUp: return cv::Rect(side.low, side.line - depth, length, depth);
    case Growth::kRight: return cv::Rect(side.line, side.low, depth, length);
    case Growth::kLeft: return cv::Rect(side.line - depth, side.low, depth, length);
  }
  return cv::Rect();
}

// The border room's pixels: the square's unknown pixels outside the other rooms, connected to the door's wall.
cv::Mat1b borderRoomMask(const common::OccupancyGrid& map, const cv::Rect& square, const BorderSide& side,
                         const cv::Mat1b& other_rooms) {
  cv::Mat1b mask = cv::Mat1b::zeros(map.cells.size());
  const cv::Rect clipped = square & cv::Rect(cv::Point(0, 0), map.cells.size());
  if (clipped.empty()) return mask;
  cv::Mat1b part = mask(clipped);
  part.setTo(255);
  part.setTo(0, map.cells(clipped) != common::OccupancyGrid::kUnknown);
  part.setTo(0, other_rooms(clipped));
  cv::Mat1i labels;
  const int count = cv::connectedComponents(part, labels, 4, CV_32S);
  std::vector<bool> keep(count, false);
  // Seeds: the square's row or column next to the door's wall.
  const bool vertical_growth = side.growth == Growth::kDown || side.growth == Growth::kUp;
  const int seed_line = side.growth == Growth::kDown || side.growth == Growth::kRight ? side.line : side.line - 1;
  for (int t = side.low; t < side.high; ++t) {
    const int x = (vertical_growth ? t : seed_line) - clipped.x, y = (vertical_growth ? seed_line : t) - clipped.y;
    if (x < 0 || y < 0 || x >= part.cols || y >= part.rows) continue;
    if (labels(y, x) > 0) keep[labels(y, x)] = true;
  }
  for (int y = 0; y < part.rows; ++y)
    for (int x = 0; x < part.cols; ++x)
      if (part(y, x) && !keep[labels(y, x)]) part(y, x) = 0;
  return mask;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------

const common::OptionTable<ThesisOptions>& thesisOptionTable() {
  using O = ThesisOptions;
  static const common::OptionTable<O> table{
      {"thesis_ind_k1", &O::ind_k1, "independent room utility: weight of co"},
      {"thesis_ind_k2", &O::ind_k2, "independent room utility: weight of fe"},
      {"thesis_ind_k3", &O::ind_k3, "independent room utility: weight of oc"},
      {"thesis_ind_k4", &O::ind_k4, "independent room utility: weight of sqrt(ar)"},
      {"thesis_dep_k1", &O::dep_k1, "dependent room utility: weight of co"},
      {"thesis_dep_k2", &O::dep_k2, "dependent room utility: weight of fe"},
      {"thesis_dep_k3", &O::dep_k3, "dependent room utility: weight of oc - cv"},
      {"thesis_dep_k4", &O::dep_k4, "dependent room utility: weight of sqrt(ar)"},
      {"thesis_dep_k5", &O::dep_k5, "dependent room utility: weight of the proportion term"},
      {"thesis_dep_cv", &O::dep_cv, "dependent room utility: outcasts tolerated"},
      {"thesis_proportion_threshold", &O::proportion_threshold,
       "pr = max(0, long side / short side - threshold)", common::atLeast(1)},
      {"thesis_outcast_min_neighbours", &O::outcast_min_neighbours,
       "a room cell with n >= this many free neighbours costs n - (this - 1)", common::between(1, 4)},
      {"thesis_depth", &O::depth, "greedy expansion steps (level of depth l)", common::between(0, 1000)},
      {"thesis_max_candidates", &O::max_candidates,
       "candidates per expansion step (2^n subsets are scored)", common::between(0, 20)},
      {"thesis_fix_pairs", &O::fix_pairs, "exchange cells between adjacent rooms (docs/method.md#pair-fix)"},
      {"thesis_fix_k1", &O::fix_k1, "pair fix score: weight of sqrt(max area / min area)"},
      {"thesis_fix_k2", &O::fix_k2, "pair fix score: weight of co_i + co_j"},
      {"thesis_max_exchangeable", &O::max_exchangeable,
       "exchangeable cells per pair (2^n assignments are scored)", common::between(0, 20)},
      {"thesis_border_rooms", &O::border_rooms, "border-cell rooms grow into squares (docs/method.md#border-rooms)"},
      {"thesis_border_depth_average", &O::border_depth_average,
       "1: border squares growing the same way share their average side as depth; 0: each keeps its own side"},
      {"thesis_border_cells_free", &O::border_cells_free, "OUT border cells count as free in fe and oc"},
  };
  return table;
}

const std::vector<std::string>& thesisParameterNames() {
  static const std::vector<std::string> names = common::optionNames(thesisOptionTable());
  return names;
}

std::map<std::string, double> thesisParameters(const ThesisOptions& options) {
  return common::optionValues(thesisOptionTable(), options);
}

ThesisOptions thesisOptionsFromParameters(const std::map<std::string, double>& parameters) {
  ThesisOptions options;
  common::applyOptionValues(thesisOptionTable(), parameters, &options, "parameter ");
  validate(options);
  return options;
}

std::vector<ThesisRoomCells> thesisRoomCells(const Layout& layout, const ThesisOptions& options) {
  const CellGrid& grid = layout.grid;
  std::vector<ThesisRoomCells> result(layout.doors.size());
  ThesisExpansion expansion(layout, options);
  std::vector<int> room_of_door(layout.doors.size(), -1);
  std::map<int, int> door_of_start;
  for (size_t d = 0; d < layout.doors.size(); ++d) {
    const DoorStart& start = layout.doors[d];
    if (!start.found) continue;
    const auto shared = door_of_start.find(start.start_cell);
    if (shared != door_of_start.end()) {
      result[d].shared_start_with = shared->second;
      continue;
    }
    door_of_start[start.start_cell] = static_cast<int>(d);
    room_of_door[d] = expansion.addRoom(static_cast<int>(d), start.start_cell, start.explored_cell);
  }

  expansion.expand();
  if (options.fix_pairs) expansion.fixPairs();

  std::vector<ThesisRoom>& rooms = expansion.rooms();
  // Border rooms (docs/method.md#border-rooms): rooms whose start cell lies on the grid's border.
  struct Square {
    int room;
    BorderSide side;
  };
  std::vector<Square> squares;
  if (options.border_rooms)
    for (size_t r = 0; r < rooms.size(); ++r) {
      ThesisRoom& room = rooms[r];
      if (!grid.cells[room.start].border) continue;
      expansion.growBorderRoom(static_cast<int>(r), grid.cells[room.explored].room);
      Square square{static_cast<int>(r), BorderSide()};
      if (borderSide(grid, layout.doors[room.door], room.cells, &square.side)) squares.push_back(square);
    }
  // Depth: the square's own side, or the average of the sides of the squares growing the same way.
  for (const Growth growth : {Growth::kUp, Growth::kDown, Growth::kLeft, Growth::kRight}) {
    double sum = 0.0;
    int count = 0;
    for (const Square& s : squares)
      if (s.side.growth == growth) {
        sum += s.side.high - s.side.low;
        ++count;
      }
    if (count == 0) continue;
    const int average = static_cast<int>(std::lround(sum / count));
    for (const Square& s : squares)
      if (s.side.growth == growth) {
        ThesisRoomCells& out = result[rooms[s.room].door];
        out.border_room = true;
        out.square = squareRect(s.side, options.border_depth_average ? average : s.side.high - s.side.low);
      }
  }

  for (size_t r = 0; r < rooms.size(); ++r) {
    ThesisRoomCells& out = result[rooms[r].door];
    out.cells = rooms[r].cells;
    std::sort(out.cells.begin(), out.cells.end());
    out.dependent = expansion.isDependent(static_cast<int>(r));
    out.candidates_capped = rooms[r].capped;
    out.exchangeable_capped = rooms[r].exchange_capped;
    out.steps = rooms[r].steps;
  }
  for (size_t d = 0; d < result.size(); ++d)
    if (result[d].shared_start_with >= 0) {
      const int shared = result[d].shared_start_with;
      result[d] = result[shared];
      result[d].shared_start_with = shared;
    }
  return result;
}

// ---------------------------------------------------------------------------------------------------------

std::map<std::string, double> ThesisPredictor::defaultParameters() const {
  std::map<std::string, double> parameters = layoutParameters(LayoutOptions());
  for (const auto& [name, value] : thesisParameters(ThesisOptions())) parameters[name] = value;
  return parameters;
}

PredictionResult ThesisPredictor::predict(const PredictionRequest& request) const {
  const auto start_time = std::chrono::steady_clock::now();
  checkUsableRequest(request);
  const std::map<std::string, double> parameters = resolveParameters(*this, request.parameters);
  std::map<std::string, double> layout_parameters;
  for (const std::string& name : layoutParameterNames()) layout_parameters[name] = parameters.at(name);
  const LayoutOptions layout_options = layoutOptionsFromParameters(layout_parameters);
  const ThesisOptions options = thesisOptionsFromParameters(parameters);
  const Layout layout = analyzeLayout(request.map, request.doors.doors, layout_options, request.debug_dir);
  const std::vector<ThesisRoomCells> rooms = thesisRoomCells(layout, options);

  // Cells of every predicted room, to keep border squares out of the others.
  std::vector<bool> owned(layout.grid.size(), false);
  std::vector<int> owner(layout.grid.size(), -1);
  for (size_t d = 0; d < rooms.size(); ++d)
    if (rooms[d].shared_start_with < 0)
      for (int c : rooms[d].cells) owner[c] = static_cast<int>(d);

  PredictionResult result;
  for (size_t d = 0; d < request.doors.doors.size(); ++d) {
    const DoorStart& start = layout.doors[d];
    const ThesisRoomCells& cells = rooms[d];
    if (!start.found) {
      result.rooms.push_back(unplacedRoom(request.map, request.doors.doors[d].id, start.problem));
      continue;
    }
    RoomPrediction room;
    if (cells.border_room) {
      std::vector<int> others;
      const int self = cells.shared_start_with >= 0 ? cells.shared_start_with : static_cast<int>(d);
      for (int c = 0; c < layout.grid.size(); ++c)
        if (owner[c] >= 0 && owner[c] != self) others.push_back(c);
      BorderSide side;
      borderSide(layout.grid, start, cells.cells, &side);
      room.door_id = start.door_id;
      room.mask = borderRoomMask(request.map, cells.square, side, cellsMask(layout, others));
      finishPrediction(request.map, &room);
    } else {
      room = roomFromCells(request.map, layout, start.door_id, cells.cells);
    }
    std::vector<bool> taken(layout.grid.size(), false);
    const int self = cells.shared_start_with >= 0 ? cells.shared_start_with : static_cast<int>(d);
    for (int c = 0; c < layout.grid.size(); ++c) taken[c] = owner[c] >= 0 && owner[c] != self;
    const ThesisTerms terms = thesisTerms(layout.grid, cells.cells, taken, options);
    room.terms["co"] = terms.co;
    room.terms["fe"] = terms.fe;
    room.terms["oc"] = terms.oc;
    room.terms["ar"] = terms.ar;
    room.terms["pr"] = terms.pr;
    room.terms["score"] = thesisScore(terms, cells.dependent, options);
    room.terms["dependent"] = cells.dependent ? 1.0 : 0.0;
    room.terms["steps"] = cells.steps;
    room.terms["cells"] = static_cast<double>(cells.cells.size());
    room.terms["border_room"] = cells.border_room ? 1.0 : 0.0;
    room.terms["candidates_capped"] = cells.candidates_capped ? 1.0 : 0.0;
    room.terms["exchangeable_capped"] = cells.exchangeable_capped ? 1.0 : 0.0;
    room.terms["start_distance"] = start.distance;
    result.rooms.push_back(std::move(room));
  }

  if (!request.debug_dir.empty()) {
    std::filesystem::create_directories(request.debug_dir);
    cv::Mat3b overlay =
        renderPredictionOverlay(request.map, roomLabels(request.map, request.doors, result.rooms), cv::Mat());
    const CellGrid& grid = layout.grid;
    for (int x : grid.xs)
      if (x >= 0 && x < overlay.cols) cv::line(overlay, {x, 0}, {x, overlay.rows - 1}, cv::Scalar(230, 200, 150), 1);
    for (int y : grid.ys)
      if (y >= 0 && y < overlay.rows) cv::line(overlay, {0, y}, {overlay.cols - 1, y}, cv::Scalar(230, 200, 150), 1);
    const std::string path = request.debug_dir + "/10_thesis_rooms.png";  // after the layout's stages
    common::writeImage(path, overlay);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

}  // namespace hidden_rooms::prediction
