#include "hidden_rooms/prediction/layout.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/input_error.h"
#include "hidden_rooms/prediction/layout_debug.h"

namespace hidden_rooms::prediction {

// ---------------------------------------------------------------------------------------------------------
// Options

const common::OptionTable<LayoutOptions>& layoutOptionTable() {
  using O = LayoutOptions;
  static const common::OptionTable<O> table{
      {"binary_threshold", &O::binary_threshold,
       "grey level: darker pixels (walls) become black before Canny", common::between(0, 255)},
      {"canny_low_threshold", &O::canny_low_threshold,
       "Canny hysteresis: lower threshold (gradient magnitude)", common::atLeast(0)},
      {"canny_high_threshold", &O::canny_high_threshold, "Canny hysteresis: upper threshold", common::atLeast(0)},
      {"canny_aperture", &O::canny_aperture, "Sobel aperture of Canny: 3, 5 or 7", common::between(3, 7)},
      {"hough_rho", &O::hough_rho, "pixels: distance step of the Hough accumulator", common::above(0)},
      {"hough_theta", &O::hough_theta, "rad: angle step of the Hough accumulator", {0, CV_PI, true, true}},
      {"hough_threshold", &O::hough_threshold,
       "m: accumulator votes, as edge length (20 votes at 0.05 m)", common::above(0)},
      {"hough_min_line_length", &O::hough_min_line_length,
       "m: shortest segment kept (7 px at 0.05 m)", common::atLeast(0)},
      {"hough_max_line_gap", &O::hough_max_line_gap,
       "m: largest gap bridged inside a segment (3 px)", common::atLeast(0)},
      {"angular_bandwidth", &O::angular_bandwidth,
       "mean-shift bandwidth of the angular clustering: 1 - cos of the angle (kernel 1) or rad (kernel 0)",
       {0, CV_PI / 2, true, true}},
      {"angular_kernel", &O::angular_kernel,
       "1: the reference code's biweight kernel on 1 - cos, unweighted; 0: a flat window in rad, by length",
       {0, 1, false, false, true}},
      {"wall_cluster_distance", &O::wall_cluster_distance,
       "m: lateral reach of one wall's segments (10 px)", common::atLeast(0)},
      {"wall_chaining", &O::wall_chaining,
       "1: a wall chains segments less than wall_cluster_distance apart (the reference code's); 0: bounded spread"},
      {"diagonal_limit", &O::diagonal_limit,
       "rad: angular clusters farther from both axes are dropped; 0: every wall kept, turned to the nearer axis",
       common::between(0, CV_PI / 4)},
      {"line_merge_distance", &O::line_merge_distance,
       "m: extended lines this close become one (no sliver cells)", common::atLeast(0)},
      {"door_pair_lines", &O::door_pair_lines, "add Algorithm 1's lines between pairs of closed doors"},
      {"boundary_offset", &O::boundary_offset,
       "m: boundary lines outside the bounding box (20 px)", common::above(0)},
      {"out_unknown_fraction", &O::out_unknown_fraction,
       "a cell with a larger fraction of unknown pixels is OUT", common::between(0, 1)},
      {"explored_outline", &O::explored_outline,
       "1: pixels outside the largest free region's outline count as unknown, the bounding box takes it in"},
      {"wall_coverage_band", &O::wall_coverage_band,
       "m: occupied pixels this close to an edge cover it", common::atLeast(0)},
      {"affinity_sigma", &O::affinity_sigma,
       "affinity of adjacent cells = exp(-wall fraction / sigma)", common::above(0)},
      {"affinity_normalized", &O::affinity_normalized,
       "1: DBSCAN's affinity is the reference code's D^-1 L, made symmetric; 0: L itself"},
      {"dbscan_eps", &O::dbscan_eps, "DBSCAN radius on the distance 1 - affinity, in (0, 1)", {0, 1, true, true}},
      {"dbscan_min_points", &O::dbscan_min_points,
       "DBSCAN core-point size (the cell itself counts)", common::atLeast(1)},
      {"door_start_fallback", &O::door_start_fallback,
       "1: a door without an IN/OUT edge starts at the more unknown cell of its nearest parallel edge"},
      {"door_search_radius", &O::door_search_radius,
       "m: a door's IN/OUT cell edge must be this close", common::above(0)},
  };
  return table;
}

const std::vector<std::string>& layoutParameterNames() {
  static const std::vector<std::string> names = common::optionNames(layoutOptionTable());
  return names;
}

std::map<std::string, double> layoutParameters(const LayoutOptions& options) {
  return common::optionValues(layoutOptionTable(), options);
}

void applyLayoutParameters(const std::map<std::string, double>& parameters, LayoutOptions* options) {
  common::applyOptionValues(layoutOptionTable(), parameters, options, "parameter ");
  validateLayoutOptions(*options);
}

LayoutOptions layoutOptionsFromParameters(const std::map<std::string, double>& parameters) {
  const std::vector<std::string>& names = layoutParameterNames();
  for (const auto& entry : parameters)
    if (std::find(names.begin(), names.end(), entry.first) == names.end())
      throw common::InputError("parameters", "unknown parameter '" + entry.first + "'");
  LayoutOptions options;
  applyLayoutParameters(parameters, &options);
  return options;
}

void validateLayoutOptions(const LayoutOptions& o) {
  common::validateOptions(layoutOptionTable(), o, "parameter ");
  if (o.canny_aperture != 3 && o.canny_aperture != 5 && o.canny_aperture != 7)
    throw common::InputError("parameter canny_aperture", "must be 3, 5 or 7, got " + std::to_string(o.canny_aperture));
}

// ---------------------------------------------------------------------------------------------------------
// Geometry helpers

double ImageSegment::angle() const {
  double angle = std::atan2(b.y() - a.y(), b.x() - a.x());
  if (angle < 0) angle += CV_PI;
  if (angle >= CV_PI) angle -= CV_PI;
  return angle;
}

std::vector<int> CellGrid::edgeNeighbours(int cell) const {
  std::vector<int> neighbours;
  const int i = column(cell), j = row(cell);
  if (i > 0) neighbours.push_back(index(i - 1, j));
  if (i + 1 < columns()) neighbours.push_back(index(i + 1, j));
  if (j > 0) neighbours.push_back(index(i, j - 1));
  if (j + 1 < rows()) neighbours.push_back(index(i, j + 1));
  return neighbours;
}

std::vector<int> CellGrid::vertexNeighbours(int cell) const {
  std::vector<int> neighbours;
  const int i = column(cell), j = row(cell);
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      if (di == 0 && dj == 0) continue;
      const int ni = i + di, nj = j + dj;
      if (ni >= 0 && ni < columns() && nj >= 0 && nj < rows()) neighbours.push_back(index(ni, nj));
    }
  return neighbours;
}

double CellGrid::wallFraction(int a, int b) const {
  if (a > b) std::swap(a, b);
  const int ia = column(a), ja = row(a), ib = column(b), jb = row(b);
  if (ja == jb && ib == ia + 1) return right_wall[a];
  if (ia == ib && jb == ja + 1) return below_wall[a];
  return -1.0;
}

bool CellGrid::sharedEdge(int a, int b, ImageSegment* edge) const {
  if (a > b) std::swap(a, b);
  const int ia = column(a), ja = row(a), ib = column(b), jb = row(b);
  if (ja == jb && ib == ia + 1) {
    edge->a = common::Point2(xs[ib], ys[ja]);
    edge->b = common::Point2(xs[ib], ys[ja + 1]);
    return true;
  }
  if (ia == ib && jb == ja + 1) {
    edge->a = common::Point2(xs[ia], ys[jb]);
    edge->b = common::Point2(xs[ia + 1], ys[jb]);
    return true;
  }
  return false;
}

int CellGrid::cellAt(const common::Point2& p) const {
  if (columns() == 0 || rows() == 0) return -1;
  if (p.x() < xs.front() || p.x() >= xs.back() || p.y() < ys.front() || p.y() >= ys.back()) return -1;
  const int i = static_cast<int>(std::upper_bound(xs.begin(), xs.end(), p.x()) - xs.begin()) - 1;
  const int j = static_cast<int>(std::upper_bound(ys.begin(), ys.end(), p.y()) - ys.begin()) - 1;
  return index(i, j);
}

cv::Mat1b cellsMask(const Layout& layout, const std::vector<int>& cells) {
  cv::Mat1b mask = cv::Mat1b::zeros(layout.image_size);
  const cv::Rect image(cv::Point(0, 0), layout.image_size);
  for (int cell : cells) {
    const cv::Rect inside = layout.grid.cells.at(cell).rect & image;
    if (inside.area() > 0) mask(inside).setTo(255);
  }
  return mask;
}

namespace {

int toPixels(double metres, double resolution, int minimum) {
  return std::max(minimum, static_cast<int>(std::lround(metres / resolution)));
}

// A distance threshold in pixels, a hair larger so that e.g. 0.15 m at 0.05 m keeps 3 px despite rounding.
double toPixelDistance(double metres, double resolution) { return metres / resolution * (1.0 + 1e-9); }

// Difference of two angles modulo pi, in [-pi/2, pi/2).
double angleDifference(double a, double b) {
  double d = std::fmod(a - b, CV_PI);
  if (d < -CV_PI / 2) d += CV_PI;
  if (d >= CV_PI / 2) d -= CV_PI;
  return d;
}

// ---------------------------------------------------------------------------------------------------------
// Angular clustering: 1-D mean shift on the segments' angles modulo pi, by one of two kernels.

// The reference code's kernel: every segment's angle seeds a mean shift whose kernel weighs an angle at
// difference d from the centre by (1 - c)^2 with c = (1 - cos d) / bandwidth (0 beyond c = 1), segments
// unweighted by length, all centres shifted until none moves more than 1e-5 rad; each segment belongs to the
// centre its own seed reached, and centres within 0.01 rad of each other are one cluster (their mean).
// `layout` has at least one segment and no clusters yet (clusterAngles).
void clusterAnglesByCosineKernel(double bandwidth, Layout* layout) {
  const std::vector<ImageSegment>& segments = layout->segments;
  const int n = static_cast<int>(segments.size());
  constexpr double kConverged = 1e-5, kSameCentre = 0.01;
  const double reach = std::acos(std::max(-1.0, 1.0 - bandwidth));  // the kernel's support, rad
  std::vector<double> sorted;
  for (const ImageSegment& segment : segments) sorted.push_back(segment.angle());
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> angles;  // repeated at -pi and +pi so that a window never wraps
  for (double shift : {-CV_PI, 0.0, CV_PI})
    for (double angle : sorted) angles.push_back(angle + shift);
  const auto shifted = [&](double centre) {
    const size_t lo = std::lower_bound(angles.begin(), angles.end(), centre - reach) - angles.begin();
    const size_t hi = std::upper_bound(angles.begin(), angles.end(), centre + reach) - angles.begin();
    double weight_sum = 0.0, moment = 0.0;
    for (size_t k = lo; k < hi; ++k) {
      const double c = (1.0 - std::cos(angles[k] - centre)) / bandwidth;
      if (c > 1.0) continue;
      const double weight = (1.0 - c) * (1.0 - c);
      weight_sum += weight;
      moment += weight * (angles[k] - centre);
    }
    return weight_sum > 0 ? common::angleModuloPi(centre + moment / weight_sum) : centre;
  };
  std::vector<double> centres(n);
  for (int s = 0; s < n; ++s) centres[s] = segments[s].angle();
  for (int iteration = 0; iteration < 1000; ++iteration) {
    double largest = 0.0;
    for (double& centre : centres) {
      const double next = shifted(centre);
      largest = std::max(largest, std::abs(angleDifference(next, centre)));
      centre = next;
    }
    if (largest <= kConverged) break;
  }
  // Centres within 0.01 rad (chained, around the circle) are one cluster at their mean.
  std::vector<int> order(n);
  for (int s = 0; s < n; ++s) order[s] = s;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return centres[a] < centres[b]; });
  std::vector<int> group(n, 0);
  for (int k = 1; k < n; ++k)
    group[order[k]] = group[order[k - 1]] +
                      (std::abs(angleDifference(centres[order[k]], centres[order[k - 1]])) <= kSameCentre ? 0 : 1);
  int groups = group[order[n - 1]] + 1;
  if (groups > 1 && std::abs(angleDifference(centres[order[0]], centres[order[n - 1]])) <= kSameCentre) {
    for (int& g : group)
      if (g == groups - 1) g = 0;
    --groups;
  }
  std::vector<double> offset_sum(groups, 0.0), reference(groups, 0.0);
  std::vector<int> members(groups, 0);
  for (int s = 0; s < n; ++s) {
    if (members[group[s]] == 0) reference[group[s]] = centres[s];
    offset_sum[group[s]] += angleDifference(centres[s], reference[group[s]]);
    ++members[group[s]];
  }
  for (int g = 0; g < groups; ++g)
    layout->angular_modes.push_back(common::angleModuloPi(reference[g] + offset_sum[g] / members[g]));
  layout->segment_angular_cluster = group;
}

// A flat kernel of +-bandwidth rad, each segment weighted by its length. Every segment's angle seeds a search;
// modes closer than the bandwidth merge; each segment joins its nearest mode, which finally becomes the weighted
// mean angle of its members. `layout` has at least one segment and no clusters yet (clusterAngles).
void clusterAnglesByFlatWindow(double bandwidth, Layout* layout) {
  const std::vector<ImageSegment>& segments = layout->segments;
  const int n = static_cast<int>(segments.size());

  // Angles sorted, repeated at -pi and +pi so that a window never needs wrapping; prefix sums of weights and
  // weighted angles give every window's mean in O(log n).
  std::vector<std::pair<double, double>> sorted;  // (angle, weight)
  for (const ImageSegment& s : segments) sorted.emplace_back(s.angle(), std::max(s.length(), 1e-6));
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> angles, weight_sum(1, 0.0), moment_sum(1, 0.0);
  for (double shift : {-CV_PI, 0.0, CV_PI})
    for (const auto& [angle, weight] : sorted) {
      angles.push_back(angle + shift);
      weight_sum.push_back(weight_sum.back() + weight);
      moment_sum.push_back(moment_sum.back() + weight * (angle + shift));
    }

  auto shiftToMode = [&](double mode) {
    for (int iteration = 0; iteration < 100; ++iteration) {
      const size_t lo = std::lower_bound(angles.begin(), angles.end(), mode - bandwidth) - angles.begin();
      const size_t hi = std::upper_bound(angles.begin(), angles.end(), mode + bandwidth) - angles.begin();
      const double weight = weight_sum[hi] - weight_sum[lo];
      if (weight <= 0) break;
      const double next = (moment_sum[hi] - moment_sum[lo]) / weight;
      const bool converged = std::abs(next - mode) < 1e-7;
      mode = common::angleModuloPi(next);
      if (converged) break;
    }
    return mode;
  };

  std::vector<double> modes;
  double previous_seed = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [angle, weight] : sorted) {
    if (std::abs(angle - previous_seed) < 1e-9) continue;  // same seed, same mode
    previous_seed = angle;
    modes.push_back(shiftToMode(angle));
  }

  // Merge modes within the bandwidth (sorted sweep, then the wrap-around pair).
  std::sort(modes.begin(), modes.end());
  std::vector<std::vector<double>> groups;
  for (double mode : modes) {
    if (!groups.empty() && std::abs(angleDifference(mode, groups.back().front())) <= bandwidth)
      groups.back().push_back(mode);
    else
      groups.push_back({mode});
  }
  if (groups.size() > 1 && std::abs(angleDifference(groups.front().front(), groups.back().front())) <= bandwidth) {
    groups.front().insert(groups.front().end(), groups.back().begin(), groups.back().end());
    groups.pop_back();
  }
  std::vector<double> merged;
  for (const auto& group : groups) {
    double offset = 0;
    for (double mode : group) offset += angleDifference(mode, group.front());
    merged.push_back(common::angleModuloPi(group.front() + offset / group.size()));
  }

  // Assign, then recentre each mode on its members.
  std::vector<double> offset_sum(merged.size(), 0.0), member_weight(merged.size(), 0.0);
  for (int s = 0; s < n; ++s) {
    const double angle = segments[s].angle();
    int best = 0;
    for (size_t m = 1; m < merged.size(); ++m)
      if (std::abs(angleDifference(angle, merged[m])) < std::abs(angleDifference(angle, merged[best]))) best = m;
    layout->segment_angular_cluster[s] = best;
    offset_sum[best] += segments[s].length() * angleDifference(angle, merged[best]);
    member_weight[best] += segments[s].length();
  }
  // Drop empty modes (renumbering the rest).
  std::vector<int> renumber(merged.size(), -1);
  for (size_t m = 0; m < merged.size(); ++m) {
    if (member_weight[m] <= 0) continue;
    renumber[m] = static_cast<int>(layout->angular_modes.size());
    layout->angular_modes.push_back(common::angleModuloPi(merged[m] + offset_sum[m] / member_weight[m]));
  }
  for (int& cluster : layout->segment_angular_cluster) cluster = renumber[cluster];
}

// Sets the segments' angular clusters and the clusters' angles by the kernel `options` names.
void clusterAngles(const LayoutOptions& options, Layout* layout) {
  layout->angular_modes.clear();
  layout->segment_angular_cluster.assign(layout->segments.size(), -1);
  if (layout->segments.empty()) return;
  if (options.angular_kernel == 1)
    clusterAnglesByCosineKernel(options.angular_bandwidth, layout);
  else
    clusterAnglesByFlatWindow(options.angular_bandwidth, layout);
}

// ---------------------------------------------------------------------------------------------------------
// Spatial clustering inside each angular cluster: segments sorted by their lateral offset (distance of their
// midpoint from a line through the origin along the cluster's angle). `chained` (the reference code's): a wall
// takes segments while each offset is less than `max_spread` pixels from the previous one, and lies at the
// median offset (the upper one of an even count). Otherwise a wall takes segments while their offset stays
// within `max_spread` of the wall's first (smallest) offset, so that it never spans more than `max_spread` across,
// and lies at the members' length-weighted mean offset. Angular clusters farther than `diagonal_limit` rad from
// both axes give no walls (0: every cluster gives walls).

void clusterWalls(double max_spread, bool chained, double diagonal_limit, Layout* layout) {
  layout->walls.clear();
  for (int cluster = 0; cluster < static_cast<int>(layout->angular_modes.size()); ++cluster) {
    const double mode = layout->angular_modes[cluster];
    const double from_axis =
        std::min(std::abs(angleDifference(mode, 0.0)), std::abs(angleDifference(mode, CV_PI / 2)));
    if (diagonal_limit > 0 && from_axis > diagonal_limit) continue;
    const common::Point2 along(std::cos(mode), std::sin(mode));
    const common::Point2 across(-along.y(), along.x());
    std::vector<std::pair<double, int>> offsets;  // (offset, segment)
    for (int s = 0; s < static_cast<int>(layout->segments.size()); ++s) {
      if (layout->segment_angular_cluster[s] != cluster) continue;
      const ImageSegment& segment = layout->segments[s];
      offsets.emplace_back(across.dot(0.5 * (segment.a + segment.b)), s);
    }
    std::sort(offsets.begin(), offsets.end());
    for (size_t first = 0; first < offsets.size();) {
      size_t end = first;
      if (chained)  // single linkage: each segment within max_spread of the previous one
        while (end < offsets.size() && (end == first || offsets[end].first - offsets[end - 1].first < max_spread))
          ++end;
      else
        while (end < offsets.size() && offsets[end].first - offsets[first].first <= max_spread) ++end;
      Wall wall;
      wall.angular_cluster = cluster;
      double weighted_offset = 0, total_length = 0;
      double t_min = std::numeric_limits<double>::infinity(), t_max = -t_min;
      for (size_t k = first; k < end; ++k) {
        const ImageSegment& segment = layout->segments[offsets[k].second];
        wall.segments.push_back(offsets[k].second);
        weighted_offset += segment.length() * offsets[k].first;
        total_length += segment.length();
        for (const common::Point2& p : {segment.a, segment.b}) {
          t_min = std::min(t_min, along.dot(p));
          t_max = std::max(t_max, along.dot(p));
        }
      }
      const double offset = chained ? offsets[first + (end - first) / 2].first : weighted_offset / total_length;
      wall.segment.a = offset * across + t_min * along;
      wall.segment.b = offset * across + t_max * along;
      layout->walls.push_back(std::move(wall));
      first = end;
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// Extended lines

// Lines of one axis closer than `merge_distance` become one. A group holding a boundary line keeps it; else
// a group with wall lines keeps their mean position and its longest wall; else (door pair lines only) the mean.
std::vector<ExtendedLine> mergeLines(std::vector<ExtendedLine> lines, double merge_distance, const Layout& layout) {
  std::sort(lines.begin(), lines.end(), [](const ExtendedLine& a, const ExtendedLine& b) {
    return a.position < b.position;
  });
  std::vector<ExtendedLine> merged;
  for (size_t first = 0; first < lines.size();) {
    size_t end = first + 1;
    while (end < lines.size() && (lines[end].position - lines[first].position <= merge_distance ||
                                  lines[end].position == lines[first].position))
      ++end;
    ExtendedLine result = lines[first];
    const auto has = [&](LineSource source) {
      return std::any_of(lines.begin() + first, lines.begin() + end,
                         [&](const ExtendedLine& line) { return line.source == source; });
    };
    const LineSource kept = has(LineSource::kBoundary) ? LineSource::kBoundary
                            : has(LineSource::kWall)   ? LineSource::kWall
                                                       : LineSource::kDoorPair;
    double position_sum = 0, longest = -1;
    int count = 0;
    for (size_t k = first; k < end; ++k) {
      if (lines[k].source != kept) continue;
      if (kept == LineSource::kBoundary) {
        result = lines[k];
        break;
      }
      position_sum += lines[k].position;
      ++count;
      if (kept == LineSource::kWall && layout.walls[lines[k].wall].segment.length() > longest) {
        longest = layout.walls[lines[k].wall].segment.length();
        result.wall = lines[k].wall;
      }
    }
    if (kept != LineSource::kBoundary) {
      result.source = kept;
      result.position = static_cast<int>(std::lround(position_sum / count));
      if (kept == LineSource::kDoorPair) result.wall = -1;
    }
    merged.push_back(result);
    first = end;
  }
  return merged;
}

// One line per wall, snapped to the nearer axis through the wall's midpoint, then merged.
std::vector<ExtendedLine> wallLines(const Layout& layout, double merge_distance) {
  std::vector<ExtendedLine> horizontal, vertical;
  for (int w = 0; w < static_cast<int>(layout.walls.size()); ++w) {
    const ImageSegment& segment = layout.walls[w].segment;
    const common::Point2 middle = 0.5 * (segment.a + segment.b);
    const common::Point2 direction = segment.b - segment.a;
    ExtendedLine line;
    line.source = LineSource::kWall;
    line.wall = w;
    if (std::abs(direction.x()) >= std::abs(direction.y())) {
      line.axis = LineAxis::kHorizontal;
      line.position = static_cast<int>(std::lround(middle.y()));
      horizontal.push_back(line);
    } else {
      line.axis = LineAxis::kVertical;
      line.position = static_cast<int>(std::lround(middle.x()));
      vertical.push_back(line);
    }
  }
  std::vector<ExtendedLine> lines = mergeLines(horizontal, merge_distance, layout);
  const std::vector<ExtendedLine> merged_vertical = mergeLines(vertical, merge_distance, layout);
  lines.insert(lines.end(), merged_vertical.begin(), merged_vertical.end());
  return lines;
}

// Algorithm 1 (docs/method.md#door-pair-lines), read for its intent: every pair of closed doors must be separated by
// a line. Doors farther apart in y than in x need a horizontal line (constant y) strictly between their y; otherwise a
// vertical line strictly between their x. When no line of that axis lies strictly between them, one is added through
// their midpoint (unless a line already lies within the merge distance of it). Lines added for earlier pairs count for
// later pairs. Only lines strictly inside the boundary are added.
void addDoorPairLines(const std::vector<common::Point2>& doors, const cv::Rect& boundary, double merge_distance,
                      std::vector<ExtendedLine>* lines) {
  for (size_t i = 0; i < doors.size(); ++i)
    for (size_t e = i + 1; e < doors.size(); ++e) {
      const common::Point2& a = doors[i];
      const common::Point2& b = doors[e];
      const bool horizontal = std::abs(a.x() - b.x()) < std::abs(a.y() - b.y());
      const LineAxis axis = horizontal ? LineAxis::kHorizontal : LineAxis::kVertical;
      const double low = horizontal ? std::min(a.y(), b.y()) : std::min(a.x(), b.x());
      const double high = horizontal ? std::max(a.y(), b.y()) : std::max(a.x(), b.x());
      const double middle = 0.5 * (low + high);
      const int position = static_cast<int>(std::lround(middle));
      bool separated = false, crowded = false;
      for (const ExtendedLine& line : *lines) {
        if (line.axis != axis) continue;
        separated |= line.position > low && line.position < high;
        crowded |= std::abs(line.position - middle) <= merge_distance;
      }
      if (separated || crowded || position <= low || position >= high) continue;
      const int lo_bound = horizontal ? boundary.y : boundary.x;
      const int hi_bound = horizontal ? boundary.br().y : boundary.br().x;
      if (position <= lo_bound || position >= hi_bound) continue;
      ExtendedLine line;
      line.axis = axis;
      line.position = position;
      line.source = LineSource::kDoorPair;
      lines->push_back(line);
    }
}

// ---------------------------------------------------------------------------------------------------------
// Cells

// Per pixel position along the line, whether an occupied pixel lies within `band` pixels across it; returned as
// prefix sums over the image range (index 0..length).
std::vector<int> coveragePrefix(const cv::Mat1b& occupied, LineAxis axis, int position, int band) {
  const int length = axis == LineAxis::kHorizontal ? occupied.cols : occupied.rows;
  std::vector<uint8_t> covered(length, 0);
  if (axis == LineAxis::kHorizontal) {
    for (int r = std::max(0, position - band); r < std::min(occupied.rows, position + band); ++r) {
      const uint8_t* row = occupied.ptr<uint8_t>(r);
      for (int c = 0; c < length; ++c) covered[c] |= row[c];
    }
  } else {
    const int c0 = std::max(0, position - band), c1 = std::min(occupied.cols, position + band);
    for (int r = 0; r < length && c0 < c1; ++r) {
      const uint8_t* row = occupied.ptr<uint8_t>(r);
      covered[r] = std::any_of(row + c0, row + c1, [](uint8_t v) { return v != 0; });
    }
  }
  std::vector<int> prefix(length + 1, 0);
  for (int k = 0; k < length; ++k) prefix[k + 1] = prefix[k] + (covered[k] ? 1 : 0);
  return prefix;
}

double coveredFraction(const std::vector<int>& prefix, int from, int to) {
  if (to <= from) return 0.0;
  const int length = static_cast<int>(prefix.size()) - 1;
  const int a = std::clamp(from, 0, length), b = std::clamp(to, 0, length);
  return static_cast<double>(prefix[b] - prefix[a]) / (to - from);
}

// Integral image of the non-zero pixels of `mask`.
cv::Mat1i pixelCountIntegral(const cv::Mat1b& mask) {
  cv::Mat1i integral;
  cv::integral(mask / 255, integral, CV_32S);
  return integral;
}

// Share of `rect` outside: the pixels of `inside` (= rect & image) counted by `integral`, plus every pixel of
// `rect` past the image.
double outsideFraction(const cv::Mat1i& integral, const cv::Rect& inside, const cv::Rect& rect) {
  double count = static_cast<double>(rect.area()) - inside.area();
  if (inside.area() > 0)
    count += integral(inside.br().y, inside.br().x) - integral(inside.y, inside.br().x) -
             integral(inside.br().y, inside.x) + integral(inside.y, inside.x);
  return count / rect.area();
}

// The explored area as the reference code sees it: the largest 8-connected region of free pixels with everything
// its outer outline encloses, 255 inside, 0 elsewhere.
cv::Mat1b exploredOutline(const common::OccupancyGrid& map) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(cv::Mat1b(map.cells == common::OccupancyGrid::kFree), contours, cv::RETR_EXTERNAL,
                   cv::CHAIN_APPROX_SIMPLE);
  cv::Mat1b inside(map.cells.size(), 0);
  if (contours.empty()) return inside;
  const auto largest = std::max_element(contours.begin(), contours.end(), [](const auto& a, const auto& b) {
    return cv::contourArea(a) < cv::contourArea(b);
  });
  cv::drawContours(inside, contours, static_cast<int>(largest - contours.begin()), 255, cv::FILLED);
  return inside;
}

// `explored`: the explored outline (exploredOutline), or empty when pixels outside it do not count as unknown.
void buildGrid(const common::OccupancyGrid& map, const LayoutOptions& options, const cv::Mat1b& explored,
               Layout* layout) {
  CellGrid& grid = layout->grid;
  grid = CellGrid();
  for (const ExtendedLine& line : layout->lines)
    (line.axis == LineAxis::kHorizontal ? grid.ys : grid.xs).push_back(line.position);
  std::sort(grid.xs.begin(), grid.xs.end());
  std::sort(grid.ys.begin(), grid.ys.end());
  grid.xs.erase(std::unique(grid.xs.begin(), grid.xs.end()), grid.xs.end());
  grid.ys.erase(std::unique(grid.ys.begin(), grid.ys.end()), grid.ys.end());

  const cv::Rect image(0, 0, map.width(), map.height());
  const cv::Mat1b unknown = map.cells == common::OccupancyGrid::kUnknown;
  const cv::Mat1i unknown_integral = pixelCountIntegral(unknown);
  const cv::Mat1i outside_integral =
      explored.empty() ? unknown_integral : pixelCountIntegral(unknown | ~explored);
  const int columns = grid.columns(), rows = grid.rows();
  grid.cells.resize(static_cast<size_t>(columns) * rows);
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      LayoutCell& cell = grid.cells[grid.index(i, j)];
      cell.rect = cv::Rect(grid.xs[i], grid.ys[j], grid.xs[i + 1] - grid.xs[i], grid.ys[j + 1] - grid.ys[j]);
      cell.border = i == 0 || j == 0 || i == columns - 1 || j == rows - 1;
      cell.unknown_fraction = outsideFraction(unknown_integral, cell.rect & image, cell.rect);
      cell.outside_fraction = outsideFraction(outside_integral, cell.rect & image, cell.rect);
      cell.out = cell.outside_fraction > options.out_unknown_fraction;
    }

  // Wall fraction of every inner edge: the share of its pixels with an occupied pixel within the band.
  const cv::Mat1b occupied = cv::Mat1b(map.cells == common::OccupancyGrid::kOccupied) / 255;
  const int band = toPixels(options.wall_coverage_band, map.resolution, 1);
  grid.right_wall.assign(grid.cells.size(), 0.0);
  grid.below_wall.assign(grid.cells.size(), 0.0);
  for (int i = 0; i + 1 < columns; ++i) {
    const std::vector<int> prefix = coveragePrefix(occupied, LineAxis::kVertical, grid.xs[i + 1], band);
    for (int j = 0; j < rows; ++j)
      grid.right_wall[grid.index(i, j)] = coveredFraction(prefix, grid.ys[j], grid.ys[j + 1]);
  }
  for (int j = 0; j + 1 < rows; ++j) {
    const std::vector<int> prefix = coveragePrefix(occupied, LineAxis::kHorizontal, grid.ys[j + 1], band);
    for (int i = 0; i < columns; ++i)
      grid.below_wall[grid.index(i, j)] = coveredFraction(prefix, grid.xs[i], grid.xs[i + 1]);
  }
}

// DBSCAN of the IN cells (docs/method.md#rooms-of-in-cells). Affinity of edge-adjacent IN cells: L = exp(-w / sigma)
// with w the wall fraction of their shared edge; with affinity_normalized, M = (L / d_a + L / d_b) / 2 with d the
// cell's degree (1 for itself plus L to each edge-adjacent IN cell), else M = L. Distance 1 - M; any other pair of
// distinct cells has affinity 0, distance 1 > eps, so a neighbourhood is the cell itself plus its edge-adjacent IN
// cells with M >= 1 - eps. With min_points 1 the rooms are the connected components of that graph. DBSCAN's noise
// cells (possible with min_points > 1) each become a room of their own, so that every IN cell has a room.
int segmentRooms(const LayoutOptions& options, CellGrid* grid) {
  const int count = grid->size();
  const int min_points = static_cast<int>(std::lround(options.dbscan_min_points));
  const auto affinity = [&](int a, int b) { return std::exp(-grid->wallFraction(a, b) / options.affinity_sigma); };
  std::vector<double> degree(count, 1.0);
  for (int cell = 0; cell < count; ++cell)
    if (!grid->cells[cell].out)
      for (int other : grid->edgeNeighbours(cell))
        if (!grid->cells[other].out) degree[cell] += affinity(cell, other);
  auto neighbourhood = [&](int cell) {
    std::vector<int> near{cell};
    for (int other : grid->edgeNeighbours(cell)) {
      if (grid->cells[other].out) continue;
      const double l = affinity(cell, other);
      const double m = options.affinity_normalized ? 0.5 * (l / degree[cell] + l / degree[other]) : l;
      if (1.0 - m <= options.dbscan_eps) near.push_back(other);
    }
    return near;
  };
  constexpr int kUnvisited = -2, kNoise = -1;
  std::vector<int> label(count, kUnvisited);
  int rooms = 0;
  for (int cell = 0; cell < count; ++cell) {
    if (grid->cells[cell].out || label[cell] != kUnvisited) continue;
    const std::vector<int> near = neighbourhood(cell);
    if (static_cast<int>(near.size()) < min_points) {
      label[cell] = kNoise;
      continue;
    }
    const int room = rooms++;
    label[cell] = room;
    std::vector<int> queue(near.begin() + 1, near.end());
    while (!queue.empty()) {
      const int next = queue.back();
      queue.pop_back();
      if (label[next] == kNoise) label[next] = room;  // border point
      if (label[next] != kUnvisited) continue;
      label[next] = room;
      const std::vector<int> next_near = neighbourhood(next);
      if (static_cast<int>(next_near.size()) >= min_points)
        queue.insert(queue.end(), next_near.begin() + 1, next_near.end());
    }
  }
  for (int cell = 0; cell < count; ++cell) {
    if (grid->cells[cell].out) continue;
    if (label[cell] == kNoise) label[cell] = rooms++;
    grid->cells[cell].room = label[cell];
  }
  return rooms;
}

// --------------------------------------------------------------------------------------------------------- Doors
// (docs/method.md#door-start-cells): the nearest grid edge between an IN and an OUT cell, preferring edges parallel
// to the door line (an O door lies on a horizontal edge, a V door on a vertical one) and falling back to the other
// orientation when no parallel edge is within the search radius; with door_start_fallback, then the nearest
// parallel edge between any two cells, its more unknown cell (which may be IN) as the start cell.

double distanceToImageSegment(const common::Point2& p, const ImageSegment& s) {
  return common::distanceToSegment(p, s.a, s.b);
}

std::vector<DoorStart> placeDoors(const common::OccupancyGrid& map, const std::vector<common::MapDoor>& doors,
                                  const LayoutOptions& options, const CellGrid& grid) {
  struct Candidate {
    int out_cell, in_cell;
    ImageSegment edge;
    bool horizontal;
  };
  // The IN/OUT edges, and with door_start_fallback the others, their more unknown cell in out_cell.
  std::vector<Candidate> candidates, other_edges;
  for (int cell = 0; cell < grid.size(); ++cell)
    for (int other : {grid.column(cell) + 1 < grid.columns() ? cell + 1 : -1,
                      grid.row(cell) + 1 < grid.rows() ? cell + grid.columns() : -1}) {
      if (other < 0) continue;
      const bool in_out = grid.cells[cell].out != grid.cells[other].out;
      if (!in_out && !options.door_start_fallback) continue;
      const bool cell_first = in_out ? grid.cells[cell].out
                                     : grid.cells[cell].unknown_fraction >= grid.cells[other].unknown_fraction;
      Candidate candidate;
      candidate.out_cell = cell_first ? cell : other;
      candidate.in_cell = cell_first ? other : cell;
      grid.sharedEdge(cell, other, &candidate.edge);
      candidate.horizontal = other != cell + 1;
      (in_out ? candidates : other_edges).push_back(candidate);
    }

  const double radius_pixels = toPixelDistance(options.door_search_radius, map.resolution);
  std::vector<DoorStart> starts;
  for (const common::MapDoor& door : doors) {
    DoorStart start;
    start.door_id = door.id;
    int col = 0, row = 0;
    if (!map.cellOf(door.position, &col, &row)) {
      start.problem = "door position (" + common::formatNumber(door.position.x()) + ", " +
                      common::formatNumber(door.position.y()) + ") is outside the map";
      starts.push_back(start);
      continue;
    }
    const common::Point2 p = map.toImage(door.position);
    const bool door_horizontal = door.orientation == common::DoorOrientation::kAlongX;
    const Candidate* best = nullptr;
    double best_distance = std::numeric_limits<double>::infinity();
    const auto find_nearest = [&](const std::vector<Candidate>& edges, bool parallel_only) {
      for (const Candidate& candidate : edges) {
        if (parallel_only && candidate.horizontal != door_horizontal) continue;
        const double distance = distanceToImageSegment(p, candidate.edge);
        if (distance <= radius_pixels && distance < best_distance) {
          best_distance = distance;
          best = &candidate;
        }
      }
    };
    find_nearest(candidates, true);
    if (best == nullptr) find_nearest(candidates, false);
    if (best == nullptr) find_nearest(other_edges, true);  // empty without door_start_fallback
    if (best == nullptr) {
      start.problem = "no cell edge between explored and unknown space within " +
                      common::formatNumber(options.door_search_radius) + " m of the door";
      starts.push_back(start);
      continue;
    }
    start.found = true;
    start.start_cell = best->out_cell;
    start.explored_cell = best->in_cell;
    start.edge = best->edge;
    const common::Point2 centre = 0.5 * (best->edge.a + best->edge.b);
    start.position = map.origin + map.resolution * common::Point2(centre.x(), map.height() - centre.y());
    start.distance = best_distance * map.resolution;
    starts.push_back(start);
  }
  return starts;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------

Layout analyzeLayout(const common::OccupancyGrid& map, const std::vector<common::MapDoor>& closed_doors,
                     const LayoutOptions& options, const std::string& debug_dir) {
  if (map.empty()) throw common::InputError("map", "the map is empty");
  if (!(map.resolution > 0.0) || !std::isfinite(map.resolution))
    throw common::InputError("map", "resolution must be positive");
  validateLayoutOptions(options);
  const double resolution = map.resolution;

  Layout layout;
  layout.image_size = map.cells.size();
  layout.resolution = resolution;

  // Walls as edges of the thresholded image (free and unknown turn white, occupied black), then segments.
  const cv::Mat1b grey = map.toGreyImage();
  cv::Mat1b binary, edges;
  cv::threshold(grey, binary, options.binary_threshold, 255, cv::THRESH_BINARY);
  cv::Canny(binary, edges, options.canny_low_threshold, options.canny_high_threshold,
            static_cast<int>(options.canny_aperture));
  std::vector<cv::Vec4i> hough;
  cv::HoughLinesP(edges, hough, options.hough_rho, options.hough_theta,
                  toPixels(options.hough_threshold, resolution, 1),
                  toPixelDistance(options.hough_min_line_length, resolution),
                  toPixelDistance(options.hough_max_line_gap, resolution));
  for (const cv::Vec4i& h : hough) {
    ImageSegment segment;  // pixel centres
    segment.a = common::Point2(h[0] + 0.5, h[1] + 0.5);
    segment.b = common::Point2(h[2] + 0.5, h[3] + 0.5);
    layout.segments.push_back(segment);
  }

  clusterAngles(options, &layout);
  clusterWalls(toPixelDistance(options.wall_cluster_distance, resolution), options.wall_chaining,
               options.diagonal_limit, &layout);

  // Bounding box of the segments (the whole image when there are none), with explored_outline of the explored
  // outline too, and the boundary lines around it.
  const cv::Mat1b explored = options.explored_outline ? exploredOutline(map) : cv::Mat1b();
  if (layout.segments.empty()) {
    layout.bounding_box = cv::Rect2d(0, 0, map.width(), map.height());
  } else {
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    for (const ImageSegment& s : layout.segments)
      for (const common::Point2& p : {s.a, s.b}) {
        x0 = std::min(x0, p.x());
        y0 = std::min(y0, p.y());
        x1 = std::max(x1, p.x());
        y1 = std::max(y1, p.y());
      }
    layout.bounding_box = cv::Rect2d(x0, y0, x1 - x0, y1 - y0);
    if (!explored.empty() && cv::countNonZero(explored) > 0)
      layout.bounding_box |= cv::Rect2d(cv::boundingRect(explored));
  }
  const int offset = toPixels(options.boundary_offset, resolution, 1);
  const cv::Rect boundary(cv::Point(static_cast<int>(std::floor(layout.bounding_box.x)) - offset,
                                    static_cast<int>(std::floor(layout.bounding_box.y)) - offset),
                          cv::Point(static_cast<int>(std::ceil(layout.bounding_box.br().x)) + offset,
                                    static_cast<int>(std::ceil(layout.bounding_box.br().y)) + offset));

  const double merge_distance = toPixelDistance(options.line_merge_distance, resolution);
  std::vector<ExtendedLine> lines = wallLines(layout, merge_distance);
  if (options.door_pair_lines != 0) {
    std::vector<common::Point2> door_points;
    for (const common::MapDoor& door : closed_doors) {
      int col = 0, row = 0;
      if (map.cellOf(door.position, &col, &row)) door_points.push_back(map.toImage(door.position));
    }
    addDoorPairLines(door_points, boundary, merge_distance, &lines);
  }
  // Boundary lines last; lines on or past them (or within the merge distance) give way.
  std::vector<ExtendedLine> horizontal, vertical;
  for (const ExtendedLine& line : lines) {
    const bool is_horizontal = line.axis == LineAxis::kHorizontal;
    const int low = is_horizontal ? boundary.y : boundary.x;
    const int high = is_horizontal ? boundary.br().y : boundary.br().x;
    if (line.position <= low || line.position >= high) continue;
    (is_horizontal ? horizontal : vertical).push_back(line);
  }
  for (int position : {boundary.y, boundary.br().y})
    horizontal.push_back({LineAxis::kHorizontal, position, LineSource::kBoundary, -1});
  for (int position : {boundary.x, boundary.br().x})
    vertical.push_back({LineAxis::kVertical, position, LineSource::kBoundary, -1});
  layout.lines = mergeLines(horizontal, merge_distance, layout);
  const std::vector<ExtendedLine> merged_vertical = mergeLines(vertical, merge_distance, layout);
  layout.lines.insert(layout.lines.end(), merged_vertical.begin(), merged_vertical.end());

  buildGrid(map, options, explored, &layout);
  layout.room_count = segmentRooms(options, &layout.grid);
  layout.doors = placeDoors(map, closed_doors, options, layout.grid);

  if (!debug_dir.empty()) writeLayoutDebugImages(debug_dir, map, closed_doors, grey, edges, explored, layout);
  return layout;
}

}  // namespace hidden_rooms::prediction
