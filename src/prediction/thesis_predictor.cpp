#include "hidden_rooms/prediction/thesis_predictor.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/common/parameter_table.h"
#include "hidden_rooms/prediction/prediction_support.h"
#include "hidden_rooms/prediction/structured_predictor.h"

namespace hidden_rooms {

namespace {

using ParameterField = hidden_rooms::ParameterField<ThesisOptions>;

const std::vector<ParameterField>& parameterFields() {
  static const std::vector<ParameterField> fields{
      {"thesis_ind_k1", &ThesisOptions::ind_k1},
      {"thesis_ind_k2", &ThesisOptions::ind_k2},
      {"thesis_ind_k3", &ThesisOptions::ind_k3},
      {"thesis_ind_k4", &ThesisOptions::ind_k4},
      {"thesis_dep_k1", &ThesisOptions::dep_k1},
      {"thesis_dep_k2", &ThesisOptions::dep_k2},
      {"thesis_dep_k3", &ThesisOptions::dep_k3},
      {"thesis_dep_k4", &ThesisOptions::dep_k4},
      {"thesis_dep_k5", &ThesisOptions::dep_k5},
      {"thesis_dep_cv", &ThesisOptions::dep_cv},
      {"thesis_proportion_threshold", &ThesisOptions::proportion_threshold},
      {"thesis_outcast_min_neighbours", &ThesisOptions::outcast_min_neighbours},
      {"thesis_depth", &ThesisOptions::depth},
      {"thesis_max_candidates", &ThesisOptions::max_candidates},
      {"thesis_fix_pairs", &ThesisOptions::fix_pairs},
      {"thesis_fix_k1", &ThesisOptions::fix_k1},
      {"thesis_fix_k2", &ThesisOptions::fix_k2},
      {"thesis_max_exchangeable", &ThesisOptions::max_exchangeable},
      {"thesis_border_rooms", &ThesisOptions::border_rooms},
      {"thesis_border_cells_free", &ThesisOptions::border_cells_free},
  };
  return fields;
}

void validate(const ThesisOptions& o) {
  requireFiniteParameters(parameterFields(), o);
  requireParameterInRange("thesis_depth", o.depth, {0, 1000, false, false, true});
  requireParameterInRange("thesis_max_candidates", o.max_candidates, {0, 20, false, false, true});
  requireParameterInRange("thesis_max_exchangeable", o.max_exchangeable, {0, 20, false, false, true});
  requireParameterInRange("thesis_fix_pairs", o.fix_pairs, {0, 1, false, false, true});
  requireParameterInRange("thesis_border_rooms", o.border_rooms, {0, 1, false, false, true});
  requireParameterInRange("thesis_border_cells_free", o.border_cells_free, {0, 1, false, false, true});
  requireParameterInRange("thesis_outcast_min_neighbours", o.outcast_min_neighbours, {1, 4, false, false, true});
  if (o.proportion_threshold < 1.0)
    throw InputError("parameters", "parameter 'thesis_proportion_threshold' must be at least 1");
}

inline int popcount(uint32_t x) { return __builtin_popcount(x); }

double outcastPenalty(int free_neighbours, const ThesisOptions& o) {
  const int min = static_cast<int>(o.outcast_min_neighbours);
  return free_neighbours >= min ? free_neighbours - (min - 1) : 0.0;
}

void addCorners(const cv::Rect& r, std::vector<cv::Point>* points) {
  points->emplace_back(r.x, r.y);
  points->emplace_back(r.x + r.width, r.y);
  points->emplace_back(r.x, r.y + r.height);
  points->emplace_back(r.x + r.width, r.y + r.height);
}

double hullArea(const std::vector<cv::Point>& points, std::vector<cv::Point>* hull) {
  if (points.size() < 3) return 0.0;
  cv::convexHull(points, *hull);
  return cv::contourArea(*hull);
}

// The hull's own vertices (a smaller point set standing for all the points).
std::vector<cv::Point> hullOf(const std::vector<cv::Point>& points) {
  if (points.size() < 3) return points;
  std::vector<cv::Point> hull;
  cv::convexHull(points, hull);
  return hull;
}

double proportions(const cv::Rect& box, const ThesisOptions& o) {
  const double long_side = std::max(box.width, box.height), short_side = std::min(box.width, box.height);
  if (short_side <= 0) return 0.0;
  return std::max(0.0, long_side / short_side - o.proportion_threshold);
}

// Edge neighbours of every cell, -1 where the grid ends.
std::vector<std::array<int, 4>> edgeNeighbourTable(const CellGrid& grid) {
  std::vector<std::array<int, 4>> table(grid.size());
  for (int c = 0; c < grid.size(); ++c) {
    const int i = grid.column(c), j = grid.row(c);
    table[c] = {i > 0 ? c - 1 : -1, i + 1 < grid.columns() ? c + 1 : -1, j > 0 ? c - grid.columns() : -1,
                j + 1 < grid.rows() ? c + grid.columns() : -1};
  }
  return table;
}

// True when `cells` (non-empty) form one region through shared edges.
bool edgeConnected(const std::vector<int>& cells, const std::vector<std::array<int, 4>>& neighbours,
                   std::vector<int>* mark, int* stamp) {
  if (cells.empty()) return false;
  const int in_set = ++*stamp, reached = ++*stamp;
  for (int c : cells) (*mark)[c] = in_set;
  std::vector<int> frontier{cells.front()};
  (*mark)[cells.front()] = reached;
  size_t count = 1;
  while (!frontier.empty()) {
    const int c = frontier.back();
    frontier.pop_back();
    for (int nb : neighbours[c])
      if (nb >= 0 && (*mark)[nb] == in_set) {
        (*mark)[nb] = reached;
        ++count;
        frontier.push_back(nb);
      }
  }
  return count == cells.size();
}

struct Room {
  int door = -1;
  int start = -1;
  int explored = -1;
  std::vector<int> cells;
  bool dependent = false;
  bool capped = false;
  bool exchange_capped = false;
  bool settled = false;
  int steps = 0;
};

// The greedy expansion, the pair fix and the border rooms over one layout.
class Expansion {
 public:
  Expansion(const Layout& layout, const ThesisOptions& options)
      : grid_(layout.grid), options_(options), neighbours_(edgeNeighbourTable(layout.grid)),
        owner_(grid_.size(), -1), mark_(grid_.size(), 0), local_(grid_.size(), -1) {}

  // Adds a room starting at `start`; returns its index.
  int addRoom(int door, int start, int explored) {
    Room room;
    room.door = door;
    room.start = start;
    room.explored = explored;
    room.cells = {start};
    owner_[start] = static_cast<int>(rooms_.size());
    rooms_.push_back(room);
    return static_cast<int>(rooms_.size()) - 1;
  }

  void expand() {
    const int depth = static_cast<int>(options_.depth);
    for (int step = 0; step < depth; ++step) {
      bool changed = false;
      for (size_t r = 0; r < rooms_.size(); ++r) {
        if (rooms_[r].settled) continue;
        const std::vector<int> added = expandOnce(static_cast<int>(r));
        if (added.empty()) {
          rooms_[r].settled = true;
          continue;
        }
        changed = true;
        ++rooms_[r].steps;
        unsettleNear(added, static_cast<int>(r));
      }
      if (!changed) break;
    }
  }

  void fixPairs() {
    for (size_t a = 0; a < rooms_.size(); ++a)
      for (size_t b = a + 1; b < rooms_.size(); ++b)
        if (adjacent(static_cast<int>(a), static_cast<int>(b))) fixPair(static_cast<int>(a), static_cast<int>(b));
  }

  // Border rooms' first stage: slide along the explored room the door leads from (docs/method.md#border-rooms).
  void growBorderRoom(int r, int explored_room) {
    Room& room = rooms_[r];
    bool grown = true;
    while (grown) {
      grown = false;
      for (size_t k = 0; k < room.cells.size(); ++k)
        for (int nb : neighbours_[room.cells[k]]) {
          if (nb < 0 || !grid_.cells[nb].out || owner_[nb] >= 0) continue;
          bool touches = false;
          for (int nn : neighbours_[nb])
            touches |= nn >= 0 && !grid_.cells[nn].out && grid_.cells[nn].room == explored_room;
          if (!touches) continue;
          owner_[nb] = r;
          room.cells.push_back(nb);
          grown = true;
        }
    }
  }

  bool isDependent(int r) const {
    for (int c : rooms_[r].cells)
      for (int nb : neighbours_[c])
        if (nb >= 0 && owner_[nb] >= 0 && owner_[nb] != r) return true;
    return false;
  }

  std::vector<bool> takenByOthers(int r) const {
    std::vector<bool> taken(grid_.size(), false);
    for (int c = 0; c < grid_.size(); ++c) taken[c] = owner_[c] >= 0 && owner_[c] != r;
    return taken;
  }

  std::vector<Room>& rooms() { return rooms_; }
  const std::vector<int>& owner() const { return owner_; }

 private:
  bool isFree(int c) const {
    return grid_.cells[c].out && owner_[c] < 0 && (options_.border_cells_free != 0.0 || !grid_.cells[c].border);
  }

  bool adjacent(int a, int b) const {
    for (int c : rooms_[a].cells)
      for (int nb : neighbours_[c])
        if (nb >= 0 && owner_[nb] == b) return true;
    return false;
  }

  void unsettleNear(const std::vector<int>& added, int changed_room) {
    for (size_t r = 0; r < rooms_.size(); ++r) {
      if (static_cast<int>(r) == changed_room || !rooms_[r].settled) continue;
      bool near = false;
      for (int c : rooms_[r].cells) {
        for (int a : added)
          if (std::abs(grid_.column(c) - grid_.column(a)) <= 2 && std::abs(grid_.row(c) - grid_.row(a)) <= 2) {
            near = true;
            break;
          }
        if (near) break;
      }
      if (near) rooms_[r].settled = false;
    }
  }

  // One step at range 0 (docs/method.md#growing-a-room): scores every connected subset of the candidates; applies the
  // best one and returns the added cells (empty when the room stays as it is).
  std::vector<int> expandOnce(int r) {
    Room& room = rooms_[r];
    room.dependent = isDependent(r);
    const bool dependent = room.dependent;

    // Candidates: OUT, non-border, free cells sharing an edge (or a corner, independent rooms) with the room.
    std::vector<int> candidates;
    std::vector<char> edge_adjacent;
    const int seen = ++stamp_;
    for (int c : room.cells) mark_[c] = seen;
    for (int c : room.cells) {
      const int i = grid_.column(c), j = grid_.row(c);
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          if (di == 0 && dj == 0) continue;
          const bool by_edge = di == 0 || dj == 0;
          if (!by_edge && dependent) continue;
          const int ni = i + di, nj = j + dj;
          if (ni < 0 || nj < 0 || ni >= grid_.columns() || nj >= grid_.rows()) continue;
          const int nb = grid_.index(ni, nj);
          if (!isFree(nb) || grid_.cells[nb].border) continue;
          if (mark_[nb] == seen) {
            // Already a candidate (or a room cell): remember an edge contact.
            if (by_edge)
              for (size_t k = 0; k < candidates.size(); ++k)
                if (candidates[k] == nb) edge_adjacent[k] = 1;
            continue;
          }
          mark_[nb] = seen;
          candidates.push_back(nb);
          edge_adjacent.push_back(by_edge ? 1 : 0);
        }
    }
    if (candidates.empty()) return {};

    // Cap: keep the candidates nearest the room (edge contacts first, then distance to the room's centre).
    const size_t cap = static_cast<size_t>(options_.max_candidates);
    if (candidates.size() > cap) {
      room.capped = true;
      cv::Rect box = grid_.cells[room.cells.front()].rect;
      for (int c : room.cells) box |= grid_.cells[c].rect;
      const Point2 centre(box.x + 0.5 * box.width, box.y + 0.5 * box.height);
      std::vector<size_t> order(candidates.size());
      std::iota(order.begin(), order.end(), 0);
      auto distance = [&](size_t k) {
        const cv::Rect& rect = grid_.cells[candidates[k]].rect;
        return (Point2(rect.x + 0.5 * rect.width, rect.y + 0.5 * rect.height) - centre).norm();
      };
      std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (edge_adjacent[a] != edge_adjacent[b]) return edge_adjacent[a] > edge_adjacent[b];
        const double da = distance(a), db = distance(b);
        if (da != db) return da < db;
        return candidates[a] < candidates[b];
      });
      order.resize(cap);
      std::sort(order.begin(), order.end());
      std::vector<int> kept;
      std::vector<char> kept_edge;
      for (size_t k : order) {
        kept.push_back(candidates[k]);
        kept_edge.push_back(edge_adjacent[k]);
      }
      candidates.swap(kept);
      edge_adjacent.swap(kept_edge);
    }
    const int n = static_cast<int>(candidates.size());
    if (n == 0) return {};
    for (int k = 0; k < n; ++k) local_[candidates[k]] = k;

    // Fixed parts of the terms.
    const int in_room = ++stamp_;
    for (int c : room.cells) mark_[c] = in_room;
    double area0 = 0.0;
    cv::Rect box0 = grid_.cells[room.cells.front()].rect;
    std::vector<cv::Point> points0;
    for (int c : room.cells) {
      area0 += static_cast<double>(grid_.cells[c].rect.area());
      box0 |= grid_.cells[c].rect;
      addCorners(grid_.cells[c].rect, &points0);
    }
    points0 = hullOf(points0);

    // Cells adjacent to the room (A0): totals, and which candidates are among them.
    const int in_a0 = ++stamp_;
    int a0_total = 0, a0_free = 0;
    uint32_t candidates_in_a0 = 0;
    for (int c : room.cells)
      for (int nb : neighbours_[c]) {
        if (nb < 0 || mark_[nb] == in_room || mark_[nb] == in_a0) continue;
        mark_[nb] = in_a0;
        ++a0_total;
        if (isFree(nb)) ++a0_free;
        if (local_[nb] >= 0) candidates_in_a0 |= 1u << local_[nb];
      }

    // Outcast: room cells touching candidates change with the subset; the others are constant.
    double oc_constant = 0.0;
    std::vector<std::pair<int, uint32_t>> touching;  // free neighbours, candidate neighbours
    for (int c : room.cells) {
      int free = 0;
      uint32_t cand = 0;
      for (int nb : neighbours_[c]) {
        if (nb < 0) continue;
        if (isFree(nb)) ++free;
        if (local_[nb] >= 0) cand |= 1u << local_[nb];
      }
      if (cand == 0)
        oc_constant += outcastPenalty(free, options_);
      else
        touching.emplace_back(free, cand);
    }

    // Per candidate: area, corners, edge-neighbour candidates, free neighbours, and its neighbours outside
    // the room, A0 and the candidates (new adjacent cells when it joins).
    struct Local {
      double area = 0.0;
      cv::Rect rect;
      uint32_t neighbours = 0;
      int free = 0;
      std::vector<std::pair<int, bool>> outer;  // cell, free
    };
    std::vector<Local> locals(n);
    uint32_t touches_room = 0;
    for (int k = 0; k < n; ++k) {
      const int c = candidates[k];
      Local& l = locals[k];
      l.rect = grid_.cells[c].rect;
      l.area = static_cast<double>(l.rect.area());
      for (int nb : neighbours_[c]) {
        if (nb < 0) continue;
        if (mark_[nb] == in_room) {
          touches_room |= 1u << k;
          continue;
        }
        const bool free = isFree(nb);
        if (free) ++l.free;
        if (local_[nb] >= 0) {
          l.neighbours |= 1u << local_[nb];
          continue;
        }
        if (mark_[nb] == in_a0) continue;
        l.outer.emplace_back(nb, free);
      }
    }

    const auto score_of = [&](const ThesisTerms& t) { return thesisScore(t, dependent, options_); };

    double best_score = -std::numeric_limits<double>::infinity();
    uint32_t best_mask = 0;
    ThesisTerms best_terms;
    std::vector<cv::Point> points, hull;
    points.reserve(points0.size() + 4 * n);
    const uint32_t full = n >= 32 ? 0xffffffffu : (1u << n) - 1u;
    for (uint64_t m = 0; m <= full; ++m) {
      const uint32_t mask = static_cast<uint32_t>(m);
      if (mask != 0) {
        // Connected to the room through shared edges.
        uint32_t reach = mask & touches_room;
        if (reach == 0) continue;
        for (;;) {
          uint32_t next = reach;
          for (uint32_t bits = reach; bits; bits &= bits - 1) next |= locals[__builtin_ctz(bits)].neighbours & mask;
          if (next == reach) break;
          reach = next;
        }
        if (reach != mask) continue;
      }
      ThesisTerms t;
      t.ar = area0;
      cv::Rect box = box0;
      points.assign(points0.begin(), points0.end());
      int total = a0_total - popcount(mask & candidates_in_a0);
      int free_count = a0_free - popcount(mask & candidates_in_a0);
      const int outer_seen = ++stamp_;
      double oc = oc_constant;
      for (const auto& [room_free, cand] : touching) oc += outcastPenalty(room_free - popcount(cand & mask), options_);
      for (uint32_t bits = mask; bits; bits &= bits - 1) {
        const int k = __builtin_ctz(bits);
        const Local& l = locals[k];
        t.ar += l.area;
        box |= l.rect;
        addCorners(l.rect, &points);
        oc += outcastPenalty(l.free - popcount(l.neighbours & mask), options_);
        // Candidates not chosen that touch this one, and outer cells: adjacent to the new room.
        for (uint32_t others = l.neighbours & ~mask & ~candidates_in_a0; others; others &= others - 1) {
          const int cell = candidates[__builtin_ctz(others)];
          if (mark_[cell] == outer_seen) continue;
          mark_[cell] = outer_seen;
          ++total;
          ++free_count;
        }
        for (const auto& [cell, cell_free] : l.outer) {
          if (mark_[cell] == outer_seen) continue;
          mark_[cell] = outer_seen;
          ++total;
          if (cell_free) ++free_count;
        }
      }
      t.fe = total > 0 ? static_cast<double>(free_count) / total : 0.0;
      t.oc = oc;
      t.co = t.ar > 0 ? std::max(0.0, hullArea(points, &hull) - t.ar) / t.ar : 0.0;
      t.pr = proportions(box, options_);
      const double s = score_of(t);
      if (s > best_score + 1e-12) {
        best_score = s;
        best_mask = mask;
        best_terms = t;
      }
    }
    for (int c : candidates) local_[c] = -1;
    // Every stamp is fresh, so the marks need no resetting.

    std::vector<int> added;
    for (uint32_t bits = best_mask; bits; bits &= bits - 1) added.push_back(candidates[__builtin_ctz(bits)]);
    for (int c : added) {
      owner_[c] = r;
      room.cells.push_back(c);
    }
    return added;
  }

  // Pair fix (docs/method.md#pair-fix): the cells added during expansion that touch the other room are exchangeable;
  // every assignment of them is scored with -k1 sqrt(max(ar)/min(ar)) - k2 (co_a + co_b); the best replaces the pair.
  void fixPair(int a, int b) {
    Room& ra = rooms_[a];
    Room& rb = rooms_[b];
    std::vector<int> exchangeable;
    for (const Room* room : {&ra, &rb}) {
      const int other = room == &ra ? b : a;
      for (int c : room->cells) {
        if (c == room->start) continue;
        bool touches = false;
        for (int nb : neighbours_[c]) touches |= nb >= 0 && owner_[nb] == other;
        if (touches) exchangeable.push_back(c);
      }
    }
    std::sort(exchangeable.begin(), exchangeable.end());
    const size_t cap = static_cast<size_t>(options_.max_exchangeable);
    if (exchangeable.size() > cap) {
      ra.exchange_capped = rb.exchange_capped = true;
      exchangeable.resize(cap);
    }
    const int n = static_cast<int>(exchangeable.size());
    if (n == 0) return;
    std::vector<int> base_a, base_b;
    const int in_x = ++stamp_;
    for (int c : exchangeable) mark_[c] = in_x;
    for (int c : ra.cells)
      if (mark_[c] != in_x) base_a.push_back(c);
    for (int c : rb.cells)
      if (mark_[c] != in_x) base_b.push_back(c);
    uint32_t current = 0;
    for (int k = 0; k < n; ++k)
      if (owner_[exchangeable[k]] == a) current |= 1u << k;

    auto room_area = [&](const std::vector<int>& cells) {
      double area = 0.0;
      for (int c : cells) area += static_cast<double>(grid_.cells[c].rect.area());
      return area;
    };
    auto convexity = [&](const std::vector<int>& cells, double area) {
      std::vector<cv::Point> points, hull;
      for (int c : cells) addCorners(grid_.cells[c].rect, &points);
      return area > 0 ? std::max(0.0, hullArea(points, &hull) - area) / area : 0.0;
    };
    auto evaluate = [&](uint32_t mask, double* score) {
      std::vector<int> cells_a = base_a, cells_b = base_b;
      for (int k = 0; k < n; ++k) ((mask >> k) & 1u ? cells_a : cells_b).push_back(exchangeable[k]);
      if (!edgeConnected(cells_a, neighbours_, &mark_, &stamp_) ||
          !edgeConnected(cells_b, neighbours_, &mark_, &stamp_))
        return false;
      const double area_a = room_area(cells_a), area_b = room_area(cells_b);
      if (area_a <= 0 || area_b <= 0) return false;
      *score = -options_.fix_k1 * std::sqrt(std::max(area_a, area_b) / std::min(area_a, area_b)) -
               options_.fix_k2 * (convexity(cells_a, area_a) + convexity(cells_b, area_b));
      return true;
    };
    double best_score = -std::numeric_limits<double>::infinity();
    uint32_t best = current;
    if (!evaluate(current, &best_score)) best_score = -std::numeric_limits<double>::infinity();
    const uint32_t full = (1u << n) - 1u;
    for (uint64_t m = 0; m <= full; ++m) {
      const uint32_t mask = static_cast<uint32_t>(m);
      if (mask == current) continue;
      double score = 0.0;
      if (evaluate(mask, &score) && score > best_score + 1e-12) {
        best_score = score;
        best = mask;
      }
    }
    if (best == current) return;
    ra.cells = base_a;
    rb.cells = base_b;
    for (int k = 0; k < n; ++k) {
      const bool to_a = (best >> k) & 1u;
      (to_a ? ra.cells : rb.cells).push_back(exchangeable[k]);
      owner_[exchangeable[k]] = to_a ? a : b;
    }
  }

  const CellGrid& grid_;
  const ThesisOptions& options_;
  std::vector<std::array<int, 4>> neighbours_;
  std::vector<int> owner_;
  std::vector<int> mark_;
  std::vector<int> local_;
  int stamp_ = 0;
  std::vector<Room> rooms_;
};

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
cv::Mat1b borderRoomMask(const OccupancyGrid& map, const cv::Rect& square, const BorderSide& side,
                         const cv::Mat1b& other_rooms) {
  cv::Mat1b mask = cv::Mat1b::zeros(map.cells.size());
  const cv::Rect clipped = square & cv::Rect(cv::Point(0, 0), map.cells.size());
  if (clipped.empty()) return mask;
  cv::Mat1b part = mask(clipped);
  part.setTo(255);
  part.setTo(0, map.cells(clipped) != OccupancyGrid::kUnknown);
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

const std::vector<std::string>& thesisParameterNames() {
  static const std::vector<std::string> names = parameterNames(parameterFields());
  return names;
}

std::map<std::string, double> thesisParameters(const ThesisOptions& options) {
  return parameterValues(parameterFields(), options);
}

ThesisOptions thesisOptionsFromParameters(const std::map<std::string, double>& parameters) {
  ThesisOptions options;
  applyParameterValues(parameterFields(), parameters, &options);
  validate(options);
  return options;
}

ThesisTerms thesisTerms(const CellGrid& grid, const std::vector<int>& cells, const std::vector<bool>& taken,
                        const ThesisOptions& options) {
  ThesisTerms terms;
  if (cells.empty()) return terms;
  std::vector<char> in_room(grid.size(), 0);
  for (int c : cells) in_room[c] = 1;
  auto is_free = [&](int c) {
    return grid.cells[c].out && !in_room[c] && (taken.empty() || !taken[c]) &&
           (options.border_cells_free != 0.0 || !grid.cells[c].border);
  };
  std::vector<cv::Point> points, hull;
  cv::Rect box = grid.cells[cells.front()].rect;
  std::vector<char> counted(grid.size(), 0);
  int total = 0, free = 0;
  for (int c : cells) {
    const cv::Rect& rect = grid.cells[c].rect;
    terms.ar += static_cast<double>(rect.area());
    box |= rect;
    addCorners(rect, &points);
    int free_neighbours = 0;
    for (int nb : grid.edgeNeighbours(c)) {
      if (in_room[nb]) continue;
      if (is_free(nb)) ++free_neighbours;
      if (counted[nb]) continue;
      counted[nb] = 1;
      ++total;
      if (is_free(nb)) ++free;
    }
    terms.oc += outcastPenalty(free_neighbours, options);
  }
  terms.fe = total > 0 ? static_cast<double>(free) / total : 0.0;
  terms.co = terms.ar > 0 ? std::max(0.0, hullArea(points, &hull) - terms.ar) / terms.ar : 0.0;
  terms.pr = proportions(box, options);
  return terms;
}

double thesisScore(const ThesisTerms& t, bool dependent, const ThesisOptions& o) {
  if (!dependent) return -o.ind_k1 * t.co - o.ind_k2 * t.fe - o.ind_k3 * t.oc + o.ind_k4 * std::sqrt(t.ar);
  return -o.dep_k1 * t.co - o.dep_k2 * t.fe - std::max(o.dep_k3 * (t.oc - o.dep_cv), 0.0) +
         o.dep_k4 * std::sqrt(t.ar) - o.dep_k5 * t.pr * std::min(t.oc, 1.0);
}

std::vector<ThesisRoomCells> thesisRoomCells(const Layout& layout, const ThesisOptions& options) {
  const CellGrid& grid = layout.grid;
  std::vector<ThesisRoomCells> result(layout.doors.size());
  Expansion expansion(layout, options);
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
  if (options.fix_pairs != 0.0) expansion.fixPairs();

  std::vector<Room>& rooms = expansion.rooms();
  // Border rooms (docs/method.md#border-rooms): rooms whose start cell lies on the grid's border.
  struct Square {
    int room;
    BorderSide side;
  };
  std::vector<Square> squares;
  if (options.border_rooms != 0.0)
    for (size_t r = 0; r < rooms.size(); ++r) {
      Room& room = rooms[r];
      if (!grid.cells[room.start].border) continue;
      expansion.growBorderRoom(static_cast<int>(r), grid.cells[room.explored].room);
      Square square{static_cast<int>(r), BorderSide()};
      if (borderSide(grid, layout.doors[room.door], room.cells, &square.side)) squares.push_back(square);
    }
  // Depth: the average of the squares' sides, per growth direction.
  for (const Growth growth : {Growth::kUp, Growth::kDown, Growth::kLeft, Growth::kRight}) {
    double sum = 0.0;
    int count = 0;
    for (const Square& s : squares)
      if (s.side.growth == growth) {
        sum += s.side.high - s.side.low;
        ++count;
      }
    if (count == 0) continue;
    const int depth = static_cast<int>(std::lround(sum / count));
    for (const Square& s : squares)
      if (s.side.growth == growth) {
        ThesisRoomCells& out = result[rooms[s.room].door];
        out.border_room = true;
        out.square = squareRect(s.side, depth);
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
  checkUsableMap(request.map);
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
    const std::string path = request.debug_dir + "/thesis_rooms.png";
    writeImage(path, overlay);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

}  // namespace hidden_rooms
