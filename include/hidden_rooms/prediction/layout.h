#pragma once

// Layout analysis of an occupancy grid map (docs/method.md#layout-analysis and #door-start-cells): walls from edge
// detection and a Hough transform, clustered by angle (mean shift) and by lateral distance; one axis-aligned extended
// line per wall, plus lines separating pairs of closed doors and four boundary lines; the rectangular cells those lines
// cut; IN/OUT cells, wall weights of the edges between cells, rooms of IN cells (DBSCAN), and the starting cell of
// every closed door.
//
// Image coordinates: x = column, y = row (row 0 at the top, as in OccupancyGrid::cells), continuous: pixel
// (c, r) covers [c, c + 1) x [r, r + 1). Extended lines sit on pixel boundaries (integers).

#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "hidden_rooms/common/doors_file.h"
#include "hidden_rooms/common/geometry.h"
#include "hidden_rooms/common/occupancy_grid.h"
#include "hidden_rooms/common/options.h"

namespace hidden_rooms::prediction {

// Parameters of the analysis. config/layout.yaml documents each one (meaning, unit, the reference
// implementation's value) and holds exactly these defaults. Lengths are metres, converted to pixels with the
// map's resolution (at least one pixel).
struct LayoutOptions {
  double binary_threshold = 150.0;         // grey level: darker pixels (walls) become black before Canny
  double canny_low_threshold = 90.0;       // Canny hysteresis thresholds (gradient magnitude)
  double canny_high_threshold = 100.0;
  int canny_aperture = 5;                  // Sobel aperture of Canny: 3, 5 or 7
  double hough_rho = 1.0;                  // pixels: distance step of the Hough accumulator
  double hough_theta = CV_PI / 180.0;      // rad: angle step of the Hough accumulator
  double hough_threshold = 1.0;            // m: accumulator votes, as edge length (20 votes at 0.05 m)
  double hough_min_line_length = 0.35;     // m: shortest segment kept (7 px at 0.05 m)
  double hough_max_line_gap = 0.15;        // m: largest gap bridged inside a segment (3 px)
  double angular_bandwidth = 0.023;        // mean-shift bandwidth: 1 - cos of the angle (kernel 1), rad (kernel 0)
  int angular_kernel = 1;                  // 1: the reference code's biweight on 1 - cos; 0: flat window in rad
  double wall_cluster_distance = 0.5;      // m: lateral reach of one wall's segments (10 px)
  bool wall_chaining = true;               // true: segments chain into a wall (the reference code's); false: bounded
  double diagonal_limit = 0.15;            // rad: angular clusters farther from both axes are dropped; 0: none
  double line_merge_distance = 0.25;       // m: extended lines this close become one (no sliver cells)
  bool door_pair_lines = true;             // add Algorithm 1's lines between pairs of closed doors
  double boundary_offset = 1.0;            // m: boundary lines outside the segments' bounding box (20 px)
  double out_unknown_fraction = 0.8;       // a cell with a larger fraction of unknown pixels is OUT
  bool explored_outline = true;            // true: pixels outside the largest free region's outline count too
  double wall_coverage_band = 0.25;        // m: occupied pixels this close to an edge cover it
  double affinity_sigma = 0.1;             // affinity of adjacent cells = exp(-wall fraction / sigma)
  bool affinity_normalized = true;         // DBSCAN on 1 - sym(D^-1 L) (the reference code's); false: on 1 - L
  double dbscan_eps = 0.85;                // DBSCAN radius on the distance 1 - affinity, in (0, 1)
  int dbscan_min_points = 1;               // DBSCAN core-point size (the cell itself counts)
  bool door_start_fallback = true;         // no IN/OUT edge: the more unknown cell of the nearest parallel edge
  double door_search_radius = 2.0;         // m: a door's IN/OUT cell edge must be this close
};

// The analysis's parameters: every LayoutOptions field by name with its range, in config/layout.yaml's order.
const common::OptionTable<LayoutOptions>& layoutOptionTable();
// Names of every LayoutOptions field, in config/layout.yaml's order.
const std::vector<std::string>& layoutParameterNames();
// The options as a name -> value map (keys = layoutParameterNames()).
std::map<std::string, double> layoutParameters(const LayoutOptions& options);
// Sets the fields named in `parameters` and ignores other names (parameters of the prediction methods), then
// validates. Throws InputError("parameters", ...) on a bad value.
void applyLayoutParameters(const std::map<std::string, double>& parameters, LayoutOptions* options);
// Defaults overridden by `parameters`; every name must be a layout parameter, else
// InputError("parameters", "unknown parameter 'x'").
LayoutOptions layoutOptionsFromParameters(const std::map<std::string, double>& parameters);
// Throws InputError("parameters", "parameter 'x' ...") when a value is out of its range.
void validateLayoutOptions(const LayoutOptions& options);

// A straight segment in image coordinates.
struct ImageSegment {
  common::Point2 a = common::Point2::Zero();
  common::Point2 b = common::Point2::Zero();
  double length() const { return (b - a).norm(); }
  // Direction angle modulo pi, in [0, pi).
  double angle() const;
};

// One wall: a cluster of parallel Hough segments less than wall_cluster_distance apart.
struct Wall {
  ImageSegment segment;       // representative: along the cluster's angle, at the length-weighted mean offset
  int angular_cluster = -1;   // index into Layout::angular_modes
  std::vector<int> segments;  // indices into Layout::segments
};

enum class LineAxis { kHorizontal, kVertical };  // horizontal: constant row y; vertical: constant column x
enum class LineSource { kWall, kDoorPair, kBoundary };

// An infinite axis-aligned line on a pixel boundary.
struct ExtendedLine {
  LineAxis axis = LineAxis::kHorizontal;
  int position = 0;  // y (horizontal) or x (vertical) in image coordinates
  LineSource source = LineSource::kWall;
  int wall = -1;     // index into Layout::walls for kWall lines (the longest wall when several merged)
};

struct LayoutCell {
  cv::Rect rect;                  // pixels covered, image coordinates; may reach past the image
  bool border = false;            // touches a boundary line
  bool out = false;               // OUT: more than out_unknown_fraction outside (see outside_fraction)
  double unknown_fraction = 0.0;  // unknown pixels; pixels past the image count
  double outside_fraction = 0.0;  // = unknown_fraction, plus with explored_outline the known pixels outside the outline
  int room = -1;                  // room (DBSCAN cluster) of an IN cell; -1 for OUT cells
};

// The cells cut by the extended lines: grid column i spans x in [xs[i], xs[i+1]), row j spans
// y in [ys[j], ys[j+1]). xs.front()/xs.back() and ys.front()/ys.back() are the boundary lines.
struct CellGrid {
  std::vector<int> xs;
  std::vector<int> ys;
  std::vector<LayoutCell> cells;      // row-major: index = j * columns() + i
  std::vector<double> right_wall;     // per cell (i, j): wall fraction of its edge with (i + 1, j)
  std::vector<double> below_wall;     // per cell (i, j): wall fraction of its edge with (i, j + 1)

  int columns() const { return xs.size() < 2 ? 0 : static_cast<int>(xs.size()) - 1; }
  int rows() const { return ys.size() < 2 ? 0 : static_cast<int>(ys.size()) - 1; }
  int size() const { return columns() * rows(); }
  int index(int i, int j) const { return j * columns() + i; }
  int column(int cell) const { return cell % columns(); }
  int row(int cell) const { return cell / columns(); }
  // Cells sharing an edge with `cell` (up to 4).
  std::vector<int> edgeNeighbours(int cell) const;
  // Cells sharing an edge or a corner with `cell` (up to 8).
  std::vector<int> vertexNeighbours(int cell) const;
  // Wall fraction of the edge shared by two edge-adjacent cells; -1 when they are not edge-adjacent.
  double wallFraction(int a, int b) const;
  // The shared edge of two edge-adjacent cells as a segment in image coordinates (false when not adjacent).
  bool sharedEdge(int a, int b, ImageSegment* edge) const;
  // The cell containing an image point, -1 outside the grid.
  int cellAt(const common::Point2& image_point) const;
};

// Where a closed door enters the cell grid (docs/method.md#door-start-cells): the nearest edge between an IN and an
// OUT cell.
struct DoorStart {
  int door_id = 0;
  bool found = false;
  std::string problem;             // why not, when !found
  int start_cell = -1;             // the OUT cell behind the door: the hidden room's first cell (door_start_fallback:
                                   // the more unknown cell of an edge between two IN or two OUT cells)
  int explored_cell = -1;          // the IN cell on the explored side of the edge (fallback: the other cell)
  ImageSegment edge;               // the shared edge, image coordinates
  common::Point2 position =
      common::Point2::Zero();      // the edge's centre in the map frame (metres): the door on the grid
  double distance = 0.0;           // metres from the door's given position to the edge
};

struct Layout {
  cv::Size image_size;
  double resolution = 0.05;
  std::vector<ImageSegment> segments;        // Hough segments
  std::vector<int> segment_angular_cluster;  // per segment, index into angular_modes
  std::vector<double> angular_modes;         // rad, in [0, pi)
  std::vector<Wall> walls;
  cv::Rect2d bounding_box;                   // of the segments' end points and, with explored_outline, of the
                                             // explored outline (image coordinates)
  std::vector<ExtendedLine> lines;           // after merging; horizontal lines first, each axis sorted
  CellGrid grid;
  int room_count = 0;                        // rooms of IN cells: LayoutCell::room in [0, room_count)
  std::vector<DoorStart> doors;              // one per closed door, same order
};

// Runs the analysis. `closed_doors` are in the map frame. When `debug_dir` is not empty it is created if
// needed and receives one image per stage (layoutDebugImageNames, layout_debug.h); InputError when it cannot be
// written. Throws InputError for an empty map or bad options.
Layout analyzeLayout(const common::OccupancyGrid& map, const std::vector<common::MapDoor>& closed_doors,
                     const LayoutOptions& options = LayoutOptions(), const std::string& debug_dir = "");

// Mask of the map's size: 255 on the pixels of the given cells (clipped to the image), 0 elsewhere.
cv::Mat1b cellsMask(const Layout& layout, const std::vector<int>& cells);

}  // namespace hidden_rooms::prediction
