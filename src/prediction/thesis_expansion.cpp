#include "hidden_rooms/prediction/thesis_expansion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <opencv2/imgproc.hpp>

namespace hidden_rooms::prediction {

namespace {

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

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Score terms

ThesisTerms thesisTerms(const CellGrid& grid, const std::vector<int>& cells, const std::vector<bool>& taken,
                        const ThesisOptions& options) {
  ThesisTerms terms;
  if (cells.empty()) return terms;
  std::vector<char> in_room(grid.size(), 0);
  for (int c : cells) in_room[c] = 1;
  auto is_free = [&](int c) {
    return grid.cells[c].out && !in_room[c] && (taken.empty() || !taken[c]) &&
           (options.border_cells_free || !grid.cells[c].border);
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

// ---------------------------------------------------------------------------------------------------------
// Rooms on the grid

ThesisExpansion::ThesisExpansion(const Layout& layout, const ThesisOptions& options)
    : grid_(layout.grid), options_(options), neighbours_(edgeNeighbourTable(layout.grid)), owner_(grid_.size(), -1),
      mark_(grid_.size(), 0), local_(grid_.size(), -1) {}

int ThesisExpansion::addRoom(int door, int start, int explored) {
  ThesisRoom room;
  room.door = door;
  room.start = start;
  room.explored = explored;
  room.cells = {start};
  owner_[start] = static_cast<int>(rooms_.size());
  rooms_.push_back(room);
  return static_cast<int>(rooms_.size()) - 1;
}

void ThesisExpansion::expand() {
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

void ThesisExpansion::fixPairs() {
  for (size_t a = 0; a < rooms_.size(); ++a)
    for (size_t b = a + 1; b < rooms_.size(); ++b)
      if (adjacent(static_cast<int>(a), static_cast<int>(b))) fixPair(static_cast<int>(a), static_cast<int>(b));
}

void ThesisExpansion::growBorderRoom(int r, int explored_room) {
  ThesisRoom& room = rooms_[r];
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

bool ThesisExpansion::isDependent(int r) const {
  for (int c : rooms_[r].cells)
    for (int nb : neighbours_[c])
      if (nb >= 0 && owner_[nb] >= 0 && owner_[nb] != r) return true;
  return false;
}

bool ThesisExpansion::isFree(int c) const {
  return grid_.cells[c].out && owner_[c] < 0 && (options_.border_cells_free || !grid_.cells[c].border);
}

bool ThesisExpansion::adjacent(int a, int b) const {
  for (int c : rooms_[a].cells)
    for (int nb : neighbours_[c])
      if (nb >= 0 && owner_[nb] == b) return true;
  return false;
}

void ThesisExpansion::unsettleNear(const std::vector<int>& added, int changed_room) {
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

// ---------------------------------------------------------------------------------------------------------
// One expansion step

// A room's candidate cells, in the order found, and per candidate whether it shares an edge with the room.
struct ThesisExpansion::Candidates {
  std::vector<int> cells;
  std::vector<char> edge_adjacent;
};

// What scoring a subset of the candidates needs (bit k of a subset = candidate k): the terms' parts that do not
// depend on the subset, and per candidate its own part.
struct ThesisExpansion::SubsetParts {
  // One candidate's part.
  struct Candidate {
    double area = 0.0;
    cv::Rect rect;
    uint32_t neighbours = 0;                  // candidates sharing an edge with it
    int free = 0;                             // free edge neighbours
    std::vector<std::pair<int, bool>> outer;  // edge neighbours outside the room, A0 and the candidates: cell, free
  };
  const std::vector<int>* candidates = nullptr;
  // The room as it is.
  double area = 0.0;
  cv::Rect box;
  std::vector<cv::Point> hull;  // vertices of the hull of its cells' corners
  // A0, the cells adjacent to the room: how many, how many free, and which candidates are among them.
  int adjacent_total = 0, adjacent_free = 0;
  uint32_t candidates_adjacent = 0;
  // Outcast: the penalty of the room cells touching no candidate, and the free and candidate neighbours of the
  // others (their penalty changes with the subset).
  double outcast_constant = 0.0;
  std::vector<std::pair<int, uint32_t>> touching;
  std::vector<Candidate> candidate_parts;
  uint32_t touches_room = 0;  // candidates sharing an edge with the room
};

std::vector<int> ThesisExpansion::expandOnce(int r) {
  ThesisRoom& room = rooms_[r];
  room.dependent = isDependent(r);
  Candidates candidates = findCandidates(room);
  if (candidates.cells.empty()) return {};
  capCandidates(&room, &candidates);
  const int n = static_cast<int>(candidates.cells.size());
  if (n == 0) return {};
  for (int k = 0; k < n; ++k) local_[candidates.cells[k]] = k;
  const uint32_t best = bestSubset(subsetParts(room, candidates.cells), room.dependent);
  for (int c : candidates.cells) local_[c] = -1;
  // Every stamp is fresh, so the marks need no resetting.

  std::vector<int> added;
  for (uint32_t bits = best; bits; bits &= bits - 1) added.push_back(candidates.cells[__builtin_ctz(bits)]);
  for (int c : added) {
    owner_[c] = r;
    room.cells.push_back(c);
  }
  return added;
}

// OUT, non-border, free cells sharing an edge (or a corner, independent rooms) with the room. Marks the room's
// cells and the candidates with a fresh stamp.
ThesisExpansion::Candidates ThesisExpansion::findCandidates(const ThesisRoom& room) {
  Candidates candidates;
  const int seen = ++stamp_;
  for (int c : room.cells) mark_[c] = seen;
  for (int c : room.cells) {
    const int i = grid_.column(c), j = grid_.row(c);
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        if (di == 0 && dj == 0) continue;
        const bool by_edge = di == 0 || dj == 0;
        if (!by_edge && room.dependent) continue;
        const int ni = i + di, nj = j + dj;
        if (ni < 0 || nj < 0 || ni >= grid_.columns() || nj >= grid_.rows()) continue;
        const int nb = grid_.index(ni, nj);
        if (!isFree(nb) || grid_.cells[nb].border) continue;
        if (mark_[nb] == seen) {
          // Already a candidate (or a room cell): remember an edge contact.
          if (by_edge)
            for (size_t k = 0; k < candidates.cells.size(); ++k)
              if (candidates.cells[k] == nb) candidates.edge_adjacent[k] = 1;
          continue;
        }
        mark_[nb] = seen;
        candidates.cells.push_back(nb);
        candidates.edge_adjacent.push_back(by_edge ? 1 : 0);
      }
  }
  return candidates;
}

// Keeps at most options.max_candidates candidates, those nearest the room (edge contacts first, then distance to
// the centre of the room's bounding box, then cell index), in their order; sets the room's capped flag when it
// drops any.
void ThesisExpansion::capCandidates(ThesisRoom* room, Candidates* candidates) const {
  const size_t cap = static_cast<size_t>(options_.max_candidates);
  const std::vector<int>& cells = candidates->cells;
  const std::vector<char>& edge_adjacent = candidates->edge_adjacent;
  if (cells.size() <= cap) return;
  room->capped = true;
  cv::Rect box = grid_.cells[room->cells.front()].rect;
  for (int c : room->cells) box |= grid_.cells[c].rect;
  const common::Point2 centre(box.x + 0.5 * box.width, box.y + 0.5 * box.height);
  std::vector<size_t> order(cells.size());
  std::iota(order.begin(), order.end(), 0);
  auto distance = [&](size_t k) {
    const cv::Rect& rect = grid_.cells[cells[k]].rect;
    return (common::Point2(rect.x + 0.5 * rect.width, rect.y + 0.5 * rect.height) - centre).norm();
  };
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    if (edge_adjacent[a] != edge_adjacent[b]) return edge_adjacent[a] > edge_adjacent[b];
    const double da = distance(a), db = distance(b);
    if (da != db) return da < db;
    return cells[a] < cells[b];
  });
  order.resize(cap);
  std::sort(order.begin(), order.end());
  Candidates kept;
  for (size_t k : order) {
    kept.cells.push_back(cells[k]);
    kept.edge_adjacent.push_back(edge_adjacent[k]);
  }
  *candidates = std::move(kept);
}

// The parts of the terms for room `room` and its `candidates` (local_ holds their indices). Marks the room's cells
// and then A0 with fresh stamps.
ThesisExpansion::SubsetParts ThesisExpansion::subsetParts(const ThesisRoom& room,
                                                          const std::vector<int>& candidates) {
  SubsetParts parts;
  parts.candidates = &candidates;
  const int in_room = ++stamp_;
  for (int c : room.cells) mark_[c] = in_room;
  addRoomShape(room, &parts);
  const int in_adjacent = ++stamp_;
  addAdjacentCells(room, in_room, in_adjacent, &parts);
  addOutcasts(room, &parts);
  addCandidateParts(in_room, in_adjacent, &parts);
  return parts;
}

// The room's area, bounding box and the hull of its cells' corners.
void ThesisExpansion::addRoomShape(const ThesisRoom& room, SubsetParts* parts) const {
  parts->box = grid_.cells[room.cells.front()].rect;
  std::vector<cv::Point> points;
  for (int c : room.cells) {
    parts->area += static_cast<double>(grid_.cells[c].rect.area());
    parts->box |= grid_.cells[c].rect;
    addCorners(grid_.cells[c].rect, &points);
  }
  parts->hull = hullOf(points);
}

// A0, the cells adjacent to the room (room cells marked `in_room`): marks them `in_adjacent` and counts them.
void ThesisExpansion::addAdjacentCells(const ThesisRoom& room, int in_room, int in_adjacent, SubsetParts* parts) {
  for (int c : room.cells)
    for (int nb : neighbours_[c]) {
      if (nb < 0 || mark_[nb] == in_room || mark_[nb] == in_adjacent) continue;
      mark_[nb] = in_adjacent;
      ++parts->adjacent_total;
      if (isFree(nb)) ++parts->adjacent_free;
      if (local_[nb] >= 0) parts->candidates_adjacent |= 1u << local_[nb];
    }
}

// Outcast: room cells touching candidates change with the subset; the others are constant.
void ThesisExpansion::addOutcasts(const ThesisRoom& room, SubsetParts* parts) const {
  for (int c : room.cells) {
    int free = 0;
    uint32_t candidate_neighbours = 0;
    for (int nb : neighbours_[c]) {
      if (nb < 0) continue;
      if (isFree(nb)) ++free;
      if (local_[nb] >= 0) candidate_neighbours |= 1u << local_[nb];
    }
    if (candidate_neighbours == 0)
      parts->outcast_constant += outcastPenalty(free, options_);
    else
      parts->touching.emplace_back(free, candidate_neighbours);
  }
}

// Per candidate: area, rectangle, candidate and free neighbours, and its neighbours outside the room (marked
// `in_room`), A0 (marked `in_adjacent`) and the candidates: new adjacent cells when it joins.
void ThesisExpansion::addCandidateParts(int in_room, int in_adjacent, SubsetParts* parts) const {
  const std::vector<int>& candidates = *parts->candidates;
  parts->candidate_parts.resize(candidates.size());
  for (size_t k = 0; k < candidates.size(); ++k) {
    const int c = candidates[k];
    SubsetParts::Candidate& l = parts->candidate_parts[k];
    l.rect = grid_.cells[c].rect;
    l.area = static_cast<double>(l.rect.area());
    for (int nb : neighbours_[c]) {
      if (nb < 0) continue;
      if (mark_[nb] == in_room) {
        parts->touches_room |= 1u << k;
        continue;
      }
      const bool free = isFree(nb);
      if (free) ++l.free;
      if (local_[nb] >= 0) {
        l.neighbours |= 1u << local_[nb];
        continue;
      }
      if (mark_[nb] == in_adjacent) continue;
      l.outer.emplace_back(nb, free);
    }
  }
}

// Whether the candidates of a non-empty `subset` are connected to the room through shared edges.
bool ThesisExpansion::connectedToRoom(uint32_t subset, const SubsetParts& parts) const {
  uint32_t reach = subset & parts.touches_room;
  if (reach == 0) return false;
  for (;;) {
    uint32_t next = reach;
    for (uint32_t bits = reach; bits; bits &= bits - 1)
      next |= parts.candidate_parts[__builtin_ctz(bits)].neighbours & subset;
    if (next == reach) break;
    reach = next;
  }
  return reach == subset;
}

// The terms of the room with the candidates of `subset` added (`points` and `hull` are scratch). Marks the cells
// counted as adjacent with a fresh stamp.
ThesisTerms ThesisExpansion::subsetTerms(uint32_t subset, const SubsetParts& parts, std::vector<cv::Point>* points,
                                         std::vector<cv::Point>* hull) {
  const std::vector<int>& candidates = *parts.candidates;
  ThesisTerms t;
  t.ar = parts.area;
  cv::Rect box = parts.box;
  points->assign(parts.hull.begin(), parts.hull.end());
  int total = parts.adjacent_total - popcount(subset & parts.candidates_adjacent);
  int free_count = parts.adjacent_free - popcount(subset & parts.candidates_adjacent);
  const int outer_seen = ++stamp_;
  double oc = parts.outcast_constant;
  for (const auto& [room_free, candidate_neighbours] : parts.touching)
    oc += outcastPenalty(room_free - popcount(candidate_neighbours & subset), options_);
  for (uint32_t bits = subset; bits; bits &= bits - 1) {
    const SubsetParts::Candidate& l = parts.candidate_parts[__builtin_ctz(bits)];
    t.ar += l.area;
    box |= l.rect;
    addCorners(l.rect, points);
    oc += outcastPenalty(l.free - popcount(l.neighbours & subset), options_);
    // Candidates not chosen that touch this one, and outer cells: adjacent to the new room.
    for (uint32_t others = l.neighbours & ~subset & ~parts.candidates_adjacent; others; others &= others - 1) {
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
  t.co = t.ar > 0 ? std::max(0.0, hullArea(*points, hull) - t.ar) / t.ar : 0.0;
  t.pr = proportions(box, options_);
  return t;
}

// The subset of the candidates, connected to the room, whose room scores best (the empty subset included; a tie
// keeps the earlier subset in counting order).
uint32_t ThesisExpansion::bestSubset(const SubsetParts& parts, bool dependent) {
  const int n = static_cast<int>(parts.candidates->size());
  double best_score = -std::numeric_limits<double>::infinity();
  uint32_t best = 0;
  std::vector<cv::Point> points, hull;
  points.reserve(parts.hull.size() + 4 * n);
  const uint32_t full = n >= 32 ? 0xffffffffu : (1u << n) - 1u;
  for (uint64_t m = 0; m <= full; ++m) {
    const uint32_t subset = static_cast<uint32_t>(m);
    if (subset != 0 && !connectedToRoom(subset, parts)) continue;
    const double score = thesisScore(subsetTerms(subset, parts, &points, &hull), dependent, options_);
    if (score > best_score + 1e-12) {
      best_score = score;
      best = subset;
    }
  }
  return best;
}

// ---------------------------------------------------------------------------------------------------------
// Pair fix

namespace {

// Area of a set of cells, pixels (whole cell rectangles).
double cellsArea(const CellGrid& grid, const std::vector<int>& cells) {
  double area = 0.0;
  for (int c : cells) area += static_cast<double>(grid.cells[c].rect.area());
  return area;
}

// The co term of a set of cells of area `area`.
double cellsConcavity(const CellGrid& grid, const std::vector<int>& cells, double area) {
  std::vector<cv::Point> points, hull;
  for (int c : cells) addCorners(grid.cells[c].rect, &points);
  return area > 0 ? std::max(0.0, hullArea(points, &hull) - area) / area : 0.0;
}

}  // namespace

// The cells of rooms a and b, but their start cells, that share an edge with the other room: sorted, at most
// options.max_exchangeable (both rooms' exchange_capped flags set when cells were dropped).
std::vector<int> ThesisExpansion::exchangeableCells(int a, int b) {
  ThesisRoom& ra = rooms_[a];
  ThesisRoom& rb = rooms_[b];
  std::vector<int> exchangeable;
  for (const ThesisRoom* room : {&ra, &rb}) {
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
  return exchangeable;
}

// Every assignment of the exchangeable cells to the two rooms that leaves both edge-connected and non-empty is
// scored with -k1 sqrt(max(ar)/min(ar)) - k2 (co_a + co_b); the best replaces the pair (the current one on a tie).
void ThesisExpansion::fixPair(int a, int b) {
  const std::vector<int> exchangeable = exchangeableCells(a, b);
  ThesisRoom& ra = rooms_[a];
  ThesisRoom& rb = rooms_[b];
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

  auto evaluate = [&](uint32_t mask, double* score) {
    std::vector<int> cells_a = base_a, cells_b = base_b;
    for (int k = 0; k < n; ++k) ((mask >> k) & 1u ? cells_a : cells_b).push_back(exchangeable[k]);
    if (!edgeConnected(cells_a, neighbours_, &mark_, &stamp_) ||
        !edgeConnected(cells_b, neighbours_, &mark_, &stamp_))
      return false;
    const double area_a = cellsArea(grid_, cells_a), area_b = cellsArea(grid_, cells_b);
    if (area_a <= 0 || area_b <= 0) return false;
    *score = -options_.fix_k1 * std::sqrt(std::max(area_a, area_b) / std::min(area_a, area_b)) -
             options_.fix_k2 * (cellsConcavity(grid_, cells_a, area_a) + cellsConcavity(grid_, cells_b, area_b));
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

}  // namespace hidden_rooms::prediction
