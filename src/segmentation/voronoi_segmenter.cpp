#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <tuple>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/segmentation/segmenters.h"

namespace hidden_rooms::segmentation {

namespace {

int squaredLength(cv::Point vector) { return vector.x * vector.x + vector.y * vector.y; }

// The boundary cells of the free space (every cell of its contours and its holes' contours, in contour order).
std::vector<std::vector<cv::Point>> freeBoundary(const cv::Mat1b& free) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(free.clone(), contours, cv::RETR_CCOMP, cv::CHAIN_APPROX_NONE);
  return contours;
}

// Step I: the generalized Voronoi graph (non-zero cells) of the boundary cells, as the survey draws it: the edges of
// the boundary cells' Voronoi cells whose two ends lie in the free space after a closing of the walls and two more
// erosions (edges near a wall come from its discretisation), kept on free cells.
cv::Mat1b voronoiGraph(const cv::Mat1b& free, const std::vector<std::vector<cv::Point>>& boundary) {
  cv::Mat1b away_from_walls;
  cv::erode(free, away_from_walls, cv::Mat());
  cv::dilate(away_from_walls, away_from_walls, cv::Mat());
  cv::erode(away_from_walls, away_from_walls, cv::Mat(), cv::Point(-1, -1), 2);

  cv::Subdiv2D subdivision(cv::Rect(0, 0, free.cols, free.rows));
  for (const std::vector<cv::Point>& contour : boundary)
    for (const cv::Point& cell : contour) subdivision.insert(cv::Point2f(cell));
  std::vector<std::vector<cv::Point2f>> facets;
  std::vector<cv::Point2f> sites;
  subdivision.getVoronoiFacetList({}, facets, sites);

  const auto away = [&](const cv::Point2f& point) {
    const cv::Point cell(static_cast<int>(point.x), static_cast<int>(point.y));  // truncated, as the survey does
    return insideImage(away_from_walls, cell) && away_from_walls(cell) != 0;
  };
  cv::Mat1b graph = cv::Mat1b::zeros(free.size());
  for (const std::vector<cv::Point2f>& facet : facets)
    for (size_t i = 0; i < facet.size(); ++i) {
      const cv::Point2f& from = facet[i == 0 ? facet.size() - 1 : i - 1];
      const cv::Point2f& to = facet[i];
      if (away(from) && away(to)) cv::line(graph, from, to, cv::Scalar(255));
    }
  graph.setTo(0, free == 0);
  return graph;
}

int graphNeighbours(const cv::Mat1b& graph, cv::Point cell) {
  int count = 0;
  for (const cv::Point& step : kNeighbours8) count += insideImage(graph, cell + step) && graph(cell + step) != 0;
  return count;
}

// Step II.1: removes the side branches: end cells (at most one graph neighbour) go, repeatedly, until a branch
// reaches a node (a cell with three or more graph neighbours before the pruning). Loops stay.
void pruneSideBranches(cv::Mat1b* graph) {
  std::vector<cv::Point> ends;
  cv::Mat1b node = cv::Mat1b::zeros(graph->size());
  for (int row = 0; row < graph->rows; ++row)
    for (int col = 0; col < graph->cols; ++col) {
      if ((*graph)(row, col) == 0) continue;
      const int neighbours = graphNeighbours(*graph, {col, row});
      if (neighbours >= 3)
        node(row, col) = 1;
      else if (neighbours <= 1)
        ends.emplace_back(col, row);
    }
  while (!ends.empty()) {
    const cv::Point cell = ends.back();
    ends.pop_back();
    if ((*graph)(cell) == 0 || node(cell) != 0 || graphNeighbours(*graph, cell) > 1) continue;
    (*graph)(cell) = 0;
    for (const cv::Point& step : kNeighbours8)
      if (insideImage(*graph, cell + step) && (*graph)(cell + step) != 0) ends.push_back(cell + step);
  }
}

// Step II.2: the critical points. The graph is cut into neighbourhoods in row-major order of their first cell: from
// it, the neighbourhood grows ring by ring along the graph over cells no earlier neighbourhood took, until it has
// counted more than neighborhood_index / clearance(first cell) cells (a cell counts once per neighbourhood cell it
// touches) or after max_rings rings. Each neighbourhood gives its cell nearest to a wall (first in row-major order
// among equals): narrow passages get long neighbourhoods, so few critical points, wide areas many.
std::vector<cv::Point> criticalPoints(const cv::Mat1b& graph, const cv::Mat1b& clearance, int neighborhood_index,
                                      int max_rings) {
  enum State : uchar { kNotGraph, kFree, kTakenThisRing, kTaken };
  cv::Mat1b state(graph.size(), kNotGraph);
  state.setTo(kFree, graph != 0);
  const auto nearer_to_wall = [&](cv::Point a, cv::Point b) {
    return std::make_tuple(clearance(a), a.y, a.x) < std::make_tuple(clearance(b), b.y, b.x);
  };
  std::vector<cv::Point> critical;
  for (int row = 0; row < state.rows; ++row)
    for (int col = 0; col < state.cols; ++col) {
      if (state(row, col) != kFree) continue;
      const cv::Point first(col, row);
      state(first) = kTaken;
      const int wanted = neighborhood_index / clearance(first);
      cv::Point lowest = first;
      std::vector<cv::Point> ring = {first};
      int counted = 0;
      for (int rings = 0; rings < max_rings && counted <= wanted && !ring.empty(); ++rings) {
        std::vector<cv::Point> next;
        for (const cv::Point& cell : ring)
          for (const cv::Point& step : kNeighbours8) {
            const cv::Point neighbour = cell + step;
            if (!insideImage(state, neighbour)) continue;
            if (state(neighbour) == kFree) {
              state(neighbour) = kTakenThisRing;
              next.push_back(neighbour);
            }
            counted += state(neighbour) == kTakenThisRing;
          }
        for (const cv::Point& cell : next) {
          state(cell) = kTaken;
          if (nearer_to_wall(cell, lowest)) lowest = cell;
        }
        ring = std::move(next);
      }
      critical.push_back(lowest);
    }
  return critical;
}

// The boundary cells indexed by position, for nearest-cell queries.
class BoundaryIndex {
 public:
  BoundaryIndex(const std::vector<std::vector<cv::Point>>& boundary, cv::Size size) : order_(size, -1) {
    int order = 0;
    for (const std::vector<cv::Point>& contour : boundary)
      for (const cv::Point& cell : contour) {
        if (order_(cell) < 0) order_(cell) = order;
        ++order;
      }
  }

  // The boundary cell nearest to `centre` among those `accepted(cell, squared distance)`, the first in contour
  // order among equally near ones; none if no cell is accepted. Searches squares of growing size around `centre`.
  template <class Accepted>
  std::optional<cv::Point> nearest(cv::Point centre, int radius, const Accepted& accepted) const {
    radius = std::max(radius, 1);
    for (;;) {
      const cv::Rect window = cv::Rect(centre.x - radius, centre.y - radius, 2 * radius + 1, 2 * radius + 1) &
                              cv::Rect(0, 0, order_.cols, order_.rows);
      std::optional<cv::Point> best;
      std::pair<int, int> best_key;  // (squared distance, contour order)
      for (int row = window.y; row < window.y + window.height; ++row)
        for (int col = window.x; col < window.x + window.width; ++col) {
          const int order = order_(row, col);
          if (order < 0) continue;
          const cv::Point cell(col, row);
          const std::pair<int, int> key(squaredLength(cell - centre), order);
          if ((!best || key < best_key) && accepted(cell, key.first)) {
            best = cell;
            best_key = key;
          }
        }
      // A cell outside the square lies farther than `radius`: the best one within that distance is the nearest.
      const bool whole_map = window.area() == order_.rows * order_.cols;
      if ((best && best_key.first <= radius * radius) || whole_map) return best;
      radius *= 2;
    }
  }

 private:
  cv::Mat1i order_;  // contour order of the boundary cell (its first occurrence), -1 elsewhere
};

// Step III: a critical line joins a critical point to its nearest boundary cell and to the nearest boundary cell
// that is farther than that one and farther from it than the point's clearance (the passage's other side).
struct CriticalLine {
  cv::Point point, first_end, second_end;
  double angle = 0.0;   // degrees between the two halves
  double length = 0.0;  // cells, both halves
};

std::optional<CriticalLine> criticalLine(const BoundaryIndex& boundary, const cv::Mat1b& clearance, cv::Point point) {
  const int own_clearance = clearance(point);
  const std::optional<cv::Point> first =
      boundary.nearest(point, own_clearance + 1, [](cv::Point, int) { return true; });
  if (!first) return std::nullopt;
  const int first_squared = squaredLength(*first - point);
  const std::optional<cv::Point> second =
      boundary.nearest(point, own_clearance + 1, [&](cv::Point cell, int squared_distance) {
        return squared_distance > first_squared && squaredLength(cell - *first) > own_clearance * own_clearance;
      });
  if (!second) return std::nullopt;
  const cv::Point2d to_first = *first - point, to_second = *second - point;
  CriticalLine line{point, *first, *second};
  const double first_length = cv::norm(to_first), second_length = cv::norm(to_second);
  const double cosine = to_first.dot(to_second) / (first_length * second_length);
  line.angle = std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / CV_PI;
  line.length = first_length + second_length;
  return line;
}

// Step III: a critical point keeps its line only if no other point nearer than `distance_factor` times its
// clearance has a wider angle, nor an equal angle and a shorter line (a line of at most 3 cells beats only the
// lines after it in the list).
std::vector<CriticalLine> linesWithTheWidestAngles(const std::vector<CriticalLine>& lines, const cv::Mat1b& clearance,
                                                   double distance_factor) {
  std::vector<CriticalLine> kept;
  for (size_t i = 0; i < lines.size(); ++i) {
    const double reach = clearance(lines[i].point) * distance_factor;
    bool keep = true;
    for (size_t j = 0; j < lines.size() && keep; ++j) {
      if (j == i || cv::norm(lines[j].point - lines[i].point) >= reach) continue;
      if (lines[i].angle < lines[j].angle) keep = false;
      if (lines[i].angle == lines[j].angle && lines[i].length > lines[j].length && (lines[j].length > 3 || i > j))
        keep = false;
    }
    if (keep) kept.push_back(lines[i]);
  }
  return kept;
}

// Step IV: the regions the critical lines (2 cells wide) separate, those whose outline encloses an area within the
// limits (cells) labelled on their outline and grown from there into every free cell they reach.
cv::Mat1i regionsBetweenLines(const cv::Mat1b& free, const std::vector<CriticalLine>& lines, double min_area,
                              double max_area) {
  cv::Mat1b cut = free.clone();
  for (const CriticalLine& line : lines) {
    cv::line(cut, line.point, line.first_end, cv::Scalar(0), 2);
    cv::line(cut, line.point, line.second_end, cv::Scalar(0), 2);
  }
  std::vector<std::vector<cv::Point>> contours;
  std::vector<cv::Vec4i> hierarchy;
  cv::findContours(cut, contours, hierarchy, cv::RETR_CCOMP, cv::CHAIN_APPROX_SIMPLE);
  cv::Mat1i labels = cv::Mat1i::zeros(free.size());
  int next_label = 0;
  for (size_t i = 0; i < contours.size(); ++i) {
    if (hierarchy[i][3] != -1) continue;  // a hole's contour
    const double area = cv::contourArea(contours[i]);
    if (area < min_area || area > max_area) continue;
    cv::drawContours(labels, contours, static_cast<int>(i), cv::Scalar(++next_label), 1);
  }
  spreadLabels(free, &labels);
  return labels;
}

// A room while the survey's merge rules run: its area and what surrounds it.
struct MergingRoom {
  double area = 0.0;          // m²
  std::map<int, int> border;  // neighbouring room (0: wall, and cells beyond the map) -> its cells touching this one

  double perimeter() const {
    double sum = 0.0;
    for (const auto& [label, cells] : border) sum += cells;
    return sum;
  }
  double share(int label) const {  // of the perimeter
    const auto found = border.find(label);
    const double total = perimeter();
    return found == border.end() || total == 0.0 ? 0.0 : found->second / total;
  }
  double wallShare() const { return share(0); }
  // Neighbouring rooms (not the wall) from the longest common border down (equal borders: lower label first).
  std::vector<int> neighboursByBorder() const {
    std::vector<int> rooms;
    for (const auto& [label, cells] : border)
      if (label != 0) rooms.push_back(label);
    std::stable_sort(rooms.begin(), rooms.end(), [&](int a, int b) { return border.at(a) > border.at(b); });
    return rooms;
  }
  int largestNeighbour() const {  // 0: none
    const std::vector<int> rooms = neighboursByBorder();
    return rooms.empty() ? 0 : rooms.front();
  }
  // Share of the perimeter that the longest borders cover, taken from the longest down until `rooms` rooms are in
  // (the wall counts if its border comes before).
  double shareOfLargestNeighbours(int rooms) const {
    std::vector<std::pair<int, int>> pieces;  // (cells, label), walls after rooms of the same length
    for (const auto& [label, cells] : border) pieces.emplace_back(cells, label);
    std::sort(pieces.begin(), pieces.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : (a.second != 0 && b.second == 0);
    });
    double sum = 0.0;
    for (const auto& [cells, label] : pieces) {
      if (rooms == 0) break;
      sum += cells;
      rooms -= label != 0;
    }
    const double total = perimeter();
    return total == 0.0 ? 0.0 : sum / total;
  }
};

// Step IV: the survey's merging of the regions into rooms. Each rule runs until it merges no more: the rooms are
// tried from the smallest up, and after every merge the rule starts again from the smallest.
class RoomMerger {
 public:
  // `labels`: rooms 1..N, 0 elsewhere.
  RoomMerger(const cv::Mat1i& labels, double cell_area) {
    double max_label = 0.0;
    cv::minMaxLoc(labels, nullptr, &max_label);
    merged_into_.assign(static_cast<size_t>(max_label) + 1, 0);
    for (const int label : labels)
      if (label > 0) rooms_[label].area += cell_area;
    cv::Mat1i padded;  // cells beyond the map are wall
    cv::copyMakeBorder(labels, padded, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    // Every cell counts once for each other room among its 8 neighbours.
    for (int row = 0; row < padded.rows; ++row)
      for (int col = 0; col < padded.cols; ++col) {
        const int label = padded(row, col);
        int touched[8];
        int count = 0;
        for (const cv::Point& step : kNeighbours8) {
          const cv::Point neighbour(col + step.x, row + step.y);
          if (!insideImage(padded, neighbour)) continue;
          const int other = padded(neighbour);
          if (other > 0 && other != label && std::find(touched, touched + count, other) == touched + count)
            touched[count++] = other;
        }
        for (int i = 0; i < count; ++i) ++rooms_[touched[i]].border[label];
      }
  }

  // Merges rooms by the rule: `target(room's label, room)` names the room to merge it into, or 0.
  template <class Rule>
  void apply(const Rule& target) {
    for (bool merged = true; merged;) {
      merged = false;
      for (const int label : bySize()) {
        const int into = target(label, rooms_.at(label));
        if (into == 0) continue;
        merge(label, into);
        merged = true;
        break;
      }
    }
  }

  const MergingRoom& room(int label) const { return rooms_.at(label); }

  // `labels` with every merged room's cells given the label of the room it ended in.
  cv::Mat1i relabelled(const cv::Mat1i& labels) const {
    cv::Mat1i result = labels.clone();
    for (int& label : result) {
      while (label > 0 && merged_into_[label] != 0) label = merged_into_[label];
    }
    return result;
  }

 private:
  std::vector<int> bySize() const {
    std::vector<int> labels;
    for (const auto& [label, room] : rooms_) labels.push_back(label);
    std::stable_sort(labels.begin(), labels.end(), [&](int a, int b) { return rooms_.at(a).area < rooms_.at(b).area; });
    return labels;
  }

  void merge(int label, int into) {
    MergingRoom& target = rooms_.at(into);
    const MergingRoom merged = rooms_.at(label);
    target.area += merged.area;
    for (const auto& [other, cells] : merged.border)
      if (other != into) target.border[other] += cells;
    target.border.erase(label);
    rooms_.erase(label);
    for (auto& [other_label, other] : rooms_) {
      const auto found = other.border.find(label);
      if (found == other.border.end()) continue;
      if (other_label != into) other.border[into] += found->second;
      other.border.erase(label);
    }
    merged_into_[label] = into;
  }

  std::map<int, MergingRoom> rooms_;
  std::vector<int> merged_into_;  // 0: still a room
};

cv::Mat1i mergeRooms(const cv::Mat1i& labels, double cell_area, double max_area_for_merging) {
  RoomMerger merger(labels, cell_area);
  // a) A part with a single neighbour, smaller than the limit and not closed off by walls (at most 75 %).
  merger.apply([&](int, const MergingRoom& room) {
    const std::vector<int> neighbours = room.neighboursByBorder();
    const bool joins = neighbours.size() == 1 && room.area < max_area_for_merging && room.wallShare() <= 0.75;
    return joins ? neighbours.front() : 0;
  });
  // b) Below 2 m², sharing over 20 % of its perimeter with its largest neighbour, unless that one is mostly walled
  // (over 80 %).
  merger.apply([&](int, const MergingRoom& room) {
    const int neighbour = room.largestNeighbour();
    const bool joins =
        neighbour != 0 && room.area < 2.0 && room.share(neighbour) > 0.2 && merger.room(neighbour).wallShare() <= 0.8;
    return joins ? neighbour : 0;
  });
  // c) Parts of one room: mostly walled (over 50 %), a single neighbour (or walls and the largest neighbour make
  // over 98 % of the perimeter) sharing over 15 %, unless that neighbour has more than two neighbours and walls and
  // its two largest neighbours make less than 95 % of its perimeter.
  merger.apply([&](int, const MergingRoom& room) {
    const int neighbour = room.largestNeighbour();
    if (neighbour == 0) return 0;
    const bool enclosed = room.neighboursByBorder().size() == 1 || room.shareOfLargestNeighbours(1) > 0.98;
    if (!enclosed || room.wallShare() <= 0.5 || room.share(neighbour) <= 0.15) return 0;
    const MergingRoom& other = merger.room(neighbour);
    const bool hub = other.neighboursByBorder().size() > 2 && other.shareOfLargestNeighbours(2) < 0.95;
    return hub ? 0 : neighbour;
  });
  // d) Rooms sharing a significant part of their perimeters: over 20 % of this one's (or over 10 % when walls make
  // up most of the rest), and over 10 % of the neighbour's. Neighbours tried from the longest border down.
  merger.apply([&](int label, const MergingRoom& room) {
    for (const int neighbour : room.neighboursByBorder()) {
      const double shared = room.share(neighbour), walls = room.wallShare();
      const bool significant =
          shared > 0.2 || (shared > 0.1 && walls > 1.0 - 2.0 * shared - 0.05 && walls < 1.0 - shared);
      if (significant && merger.room(neighbour).share(label) > 0.1) return neighbour;
    }
    return 0;
  });
  // e) The largest neighbour touches over 40 % of the perimeter (often furniture splitting a room).
  merger.apply([&](int, const MergingRoom& room) {
    const int neighbour = room.largestNeighbour();
    return neighbour != 0 && room.share(neighbour) > 0.4 ? neighbour : 0;
  });
  return merger.relabelled(labels);
}

}  // namespace

std::map<std::string, double> VoronoiSegmenter::defaultParameters() const {
  // The survey's defaults (ipa_room_segmentation: voronoi_neighborhood_index, max_iterations,
  // min_critical_point_distance_factor, max_area_for_merging, room_area_factor_{lower,upper}_limit_voronoi).
  return {
      {"voronoi_neighborhood_index", 280},
      {"voronoi_max_iterations", 150},
      {"voronoi_min_critical_point_distance_factor", 0.5},
      {"voronoi_max_area_for_merging", 12.5},
      {"voronoi_min_region_area", 0.1},
      {"voronoi_max_region_area", 1000000.0},
  };
}

cv::Mat1i VoronoiSegmenter::segment(const SegmentationInput& input,
                                    const std::map<std::string, double>& parameters) const {
  const double cell_area = input.resolution * input.resolution;
  const cv::Mat1b& free = input.free;
  const std::vector<std::vector<cv::Point>> boundary = freeBoundary(free);
  // Cells to the nearest wall, rounded (the survey works with whole cells here).
  cv::Mat1f distance;
  cv::distanceTransform(free, distance, cv::DIST_L2, 5);
  cv::Mat1b clearance;
  cv::convertScaleAbs(distance, clearance);

  cv::Mat1b graph = voronoiGraph(free, boundary);
  pruneSideBranches(&graph);
  const std::vector<cv::Point> points =
      criticalPoints(graph, clearance, static_cast<int>(parameters.at("voronoi_neighborhood_index")),
                     static_cast<int>(parameters.at("voronoi_max_iterations")));

  const BoundaryIndex boundary_index(boundary, free.size());
  std::vector<CriticalLine> lines;
  for (const cv::Point& point : points)
    if (const std::optional<CriticalLine> line = criticalLine(boundary_index, clearance, point)) lines.push_back(*line);
  lines = linesWithTheWidestAngles(lines, clearance, parameters.at("voronoi_min_critical_point_distance_factor"));

  const cv::Mat1i regions = regionsBetweenLines(free, lines, parameters.at("voronoi_min_region_area") / cell_area,
                                                parameters.at("voronoi_max_region_area") / cell_area);
  return mergeRooms(regions, cell_area, parameters.at("voronoi_max_area_for_merging"));
}

}  // namespace hidden_rooms::segmentation
