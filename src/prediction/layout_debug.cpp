#include "hidden_rooms/prediction/layout_debug.h"

#include <cmath>
#include <cstdint>
#include <filesystem>

#include <opencv2/imgproc.hpp>

#include "hidden_rooms/common/image_io.h"
#include "hidden_rooms/common/file_io.h"
#include "hidden_rooms/common/input_error.h"

namespace hidden_rooms::prediction {

namespace {

cv::Scalar paletteColour(int k) {
  cv::Mat3b hsv(1, 1, cv::Vec3b(static_cast<uint8_t>(std::fmod(k * 137.508, 360.0) / 2), 210, 225));
  cv::Mat3b bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return cv::Scalar(bgr(0, 0)[0], bgr(0, 0)[1], bgr(0, 0)[2]);
}

// A canvas covering the image and the cell grid, with the map drawn at its place.
class DebugCanvas {
 public:
  DebugCanvas(const Layout& layout, const cv::Mat1b& grey) : grey_(grey) {
    cv::Rect bounds(cv::Point(0, 0), layout.image_size);
    const CellGrid& grid = layout.grid;
    if (grid.columns() > 0 && grid.rows() > 0)
      bounds |= cv::Rect(cv::Point(grid.xs.front(), grid.ys.front()),
                         cv::Point(grid.xs.back() + 1, grid.ys.back() + 1));
    offset_ = -bounds.tl();
    size_ = bounds.size();
  }

  // The map in colour, faded towards white by `fade` in [0, 1]; the area past the image is unknown grey.
  cv::Mat3b map(double fade = 0.0) const {
    cv::Mat3b canvas(size_, cv::Vec3b(205, 205, 205));
    cv::Mat3b colour;
    cv::cvtColor(grey_, colour, cv::COLOR_GRAY2BGR);
    colour.copyTo(canvas(cv::Rect(offset_, grey_.size())));
    if (fade > 0) canvas = canvas * (1.0 - fade) + cv::Scalar::all(255 * fade);
    return canvas;
  }

  cv::Point at(const common::Point2& p) const {
    return cv::Point(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))) + offset_;
  }
  cv::Rect at(const cv::Rect& r) const { return cv::Rect(r.tl() + offset_, r.size()) & cv::Rect(cv::Point(), size_); }
  cv::Size size() const { return size_; }

  // Occupied pixels of the map drawn black over `canvas`.
  void drawWalls(cv::Mat3b* canvas) const {
    (*canvas)(cv::Rect(offset_, grey_.size())).setTo(cv::Scalar::all(0), grey_ == 0);
  }

  void drawGridLines(const Layout& layout, cv::Mat3b* canvas, const cv::Scalar& colour) const {
    const CellGrid& grid = layout.grid;
    if (grid.columns() == 0 || grid.rows() == 0) return;
    for (int x : grid.xs)
      cv::line(*canvas, at(common::Point2(x, grid.ys.front())), at(common::Point2(x, grid.ys.back())), colour, 1);
    for (int y : grid.ys)
      cv::line(*canvas, at(common::Point2(grid.xs.front(), y)), at(common::Point2(grid.xs.back(), y)), colour, 1);
  }

 private:
  cv::Mat1b grey_;
  cv::Point offset_;
  cv::Size size_;
};

void writeImage(const std::string& dir, const std::string& name, const cv::Mat& image) {
  const std::string path = (std::filesystem::path(dir) / name).string();
  hidden_rooms::common::writeImage(path, image);
}

void blend(cv::Mat3b* canvas, const cv::Rect& rect, const cv::Scalar& colour, double alpha) {
  if (rect.area() <= 0) return;
  cv::Mat3b region = (*canvas)(rect);
  cv::Mat3b tint(region.size(), cv::Vec3b(colour[0], colour[1], colour[2]));
  cv::addWeighted(region, 1.0 - alpha, tint, alpha, 0.0, region);
}

// 02_segments.png: the Hough segments in red over the half-faded map.
cv::Mat3b segmentsImage(const DebugCanvas& canvas, const Layout& layout) {
  cv::Mat3b segments = canvas.map(0.5);
  for (const ImageSegment& s : layout.segments)
    cv::line(segments, canvas.at(s.a), canvas.at(s.b), cv::Scalar(0, 0, 255), 1);
  return segments;
}

// 03_explored_outline.png: the explored outline (the reference code's outer contour of the largest free region) filled light green with its
// contour in dark green, over the half-faded map, and the bounding box the boundary lines are placed around in blue;
// without explored_outline (`explored` empty) the box alone.
cv::Mat3b exploredOutlineImage(const DebugCanvas& canvas, const Layout& layout, const cv::Mat1b& explored) {
  cv::Mat3b outline = canvas.map(0.5);
  if (!explored.empty()) {
    cv::Mat1b placed = cv::Mat1b::zeros(outline.size());
    explored.copyTo(placed(canvas.at(cv::Rect(cv::Point(0, 0), explored.size()))));
    cv::Mat3b tinted = outline * 0.6 + cv::Scalar(60, 160, 60) * 0.4;
    tinted.copyTo(outline, placed);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(placed, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    cv::drawContours(outline, contours, -1, cv::Scalar(0, 110, 0), 1);
  }
  const cv::Rect2d& box = layout.bounding_box;
  cv::rectangle(outline, canvas.at(common::Point2(box.x, box.y)), canvas.at(common::Point2(box.br().x, box.br().y)),
                cv::Scalar(200, 80, 0), 1);
  return outline;
}

// 04_angular_clusters.png: the segments coloured by angular cluster, with the clusters' angles listed.
cv::Mat3b angularClustersImage(const DebugCanvas& canvas, const Layout& layout) {
  cv::Mat3b angular = canvas.map(0.7);
  for (size_t s = 0; s < layout.segments.size(); ++s)
    cv::line(angular, canvas.at(layout.segments[s].a), canvas.at(layout.segments[s].b),
             paletteColour(layout.segment_angular_cluster[s]), 2);
  for (int m = 0; m < static_cast<int>(layout.angular_modes.size()); ++m) {
    double degrees = layout.angular_modes[m] * 180.0 / CV_PI;  // shown in [-45, 135): 179.9 as -0.1
    if (degrees >= 135.0) degrees -= 180.0;
    cv::putText(angular, common::formatNumber(std::round(degrees * 10) / 10 + 0.0) + " deg", cv::Point(5, 15 + 15 * m),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, paletteColour(m), 1);
  }
  return angular;
}

// 05_walls.png: per wall its segments in a light shade of its colour and its representative segment.
cv::Mat3b wallsImage(const DebugCanvas& canvas, const Layout& layout) {
  cv::Mat3b walls = canvas.map(0.7);
  for (size_t w = 0; w < layout.walls.size(); ++w) {
    const cv::Scalar colour = paletteColour(static_cast<int>(w));
    for (int s : layout.walls[w].segments)
      cv::line(walls, canvas.at(layout.segments[s].a), canvas.at(layout.segments[s].b),
               colour * 0.5 + cv::Scalar::all(127), 1);
    cv::line(walls, canvas.at(layout.walls[w].segment.a), canvas.at(layout.walls[w].segment.b), colour, 2);
  }
  return walls;
}

// 06_extended_lines.png: the extended lines coloured by source (with a legend) and the closed doors as red circles.
cv::Mat3b extendedLinesImage(const DebugCanvas& canvas, const common::OccupancyGrid& map,
                             const std::vector<common::MapDoor>& doors, const Layout& layout) {
  const CellGrid& grid = layout.grid;
  const bool has_grid = grid.columns() > 0 && grid.rows() > 0;
  cv::Mat3b lines = canvas.map(0.5);
  if (has_grid)
    for (const ExtendedLine& line : layout.lines) {
      const cv::Scalar colour = line.source == LineSource::kWall       ? cv::Scalar(200, 80, 0)
                                : line.source == LineSource::kDoorPair ? cv::Scalar(200, 0, 200)
                                                                       : cv::Scalar(0, 160, 0);
      const bool horizontal = line.axis == LineAxis::kHorizontal;
      const common::Point2 a =
          horizontal ? common::Point2(grid.xs.front(), line.position) : common::Point2(line.position, grid.ys.front());
      const common::Point2 b =
          horizontal ? common::Point2(grid.xs.back(), line.position) : common::Point2(line.position, grid.ys.back());
      cv::line(lines, canvas.at(a), canvas.at(b), colour, 1);
    }
  for (const common::MapDoor& door : doors)
    cv::circle(lines, canvas.at(map.toImage(door.position)), 4, cv::Scalar(0, 0, 255), 2);
  cv::putText(lines, "wall", cv::Point(5, 15), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(200, 80, 0), 1);
  cv::putText(lines, "door pair", cv::Point(5, 30), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(200, 0, 200), 1);
  cv::putText(lines, "boundary", cv::Point(5, 45), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 160, 0), 1);
  return lines;
}

// 07_cells.png: IN white, OUT grey, border cells tinted orange; the map's walls in black; grid lines light blue;
// the faded map past the grid.
cv::Mat3b cellsImage(const DebugCanvas& canvas, const Layout& layout) {
  cv::Mat3b cells = canvas.map(0.6);
  for (const LayoutCell& cell : layout.grid.cells) {
    const cv::Rect rect = canvas.at(cell.rect);
    cells(rect).setTo(cell.out ? cv::Scalar::all(150) : cv::Scalar::all(255));
    if (cell.border) blend(&cells, rect, cv::Scalar(0, 140, 255), 0.35);
  }
  canvas.drawWalls(&cells);
  canvas.drawGridLines(layout, &cells, cv::Scalar(230, 190, 120));
  return cells;
}

// 08_rooms.png: IN cells coloured by room, OUT cells grey (border cells darker).
cv::Mat3b roomsImage(const DebugCanvas& canvas, const Layout& layout) {
  cv::Mat3b rooms = canvas.map(0.6);
  for (const LayoutCell& cell : layout.grid.cells) {
    const cv::Rect rect = canvas.at(cell.rect);
    rooms(rect).setTo(!cell.out     ? paletteColour(cell.room) * 0.6 + cv::Scalar::all(100)
                      : cell.border ? cv::Scalar::all(120)
                                    : cv::Scalar::all(150));
  }
  canvas.drawWalls(&rooms);
  canvas.drawGridLines(layout, &rooms, cv::Scalar(90, 90, 90));
  return rooms;
}

// 09_start_cells.png: per door its start cell tinted in its colour and its edge in red, or a red cross where it was
// not placed; each labelled with its id.
cv::Mat3b startCellsImage(const DebugCanvas& canvas, const common::OccupancyGrid& map,
                          const std::vector<common::MapDoor>& doors, const Layout& layout) {
  cv::Mat3b starts = canvas.map(0.3);
  canvas.drawGridLines(layout, &starts, cv::Scalar(230, 190, 120));
  for (size_t d = 0; d < layout.doors.size() && d < doors.size(); ++d) {
    const DoorStart& start = layout.doors[d];
    const cv::Point door = canvas.at(map.toImage(doors[d].position));
    const cv::Scalar colour = paletteColour(static_cast<int>(d));
    if (start.found) {
      blend(&starts, canvas.at(layout.grid.cells[start.start_cell].rect), colour, 0.5);
      cv::line(starts, canvas.at(start.edge.a), canvas.at(start.edge.b), cv::Scalar(0, 0, 255), 3);
      cv::circle(starts, door, 4, cv::Scalar(0, 0, 0), 2);
    } else {
      cv::drawMarker(starts, door, cv::Scalar(0, 0, 255), cv::MARKER_TILTED_CROSS, 12, 2);
    }
    cv::putText(starts, std::to_string(doors[d].id), door + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(0, 0, 0), 2);
  }
  return starts;
}

}  // namespace

const std::vector<std::string>& layoutDebugImageNames() {
  static const std::vector<std::string> names{
      "01_edges.png",  "02_segments.png",       "03_explored_outline.png", "04_angular_clusters.png", "05_walls.png",
      "06_extended_lines.png", "07_cells.png", "08_rooms.png",            "09_start_cells.png"};
  return names;
}

void writeLayoutDebugImages(const std::string& dir, const common::OccupancyGrid& map,
                            const std::vector<common::MapDoor>& closed_doors, const cv::Mat1b& grey,
                            const cv::Mat1b& edges, const cv::Mat1b& explored, const Layout& layout) {
  common::createOutputDirectory(dir);

  const DebugCanvas canvas(layout, grey);
  const std::vector<cv::Mat> images{edges,
                                    segmentsImage(canvas, layout),
                                    exploredOutlineImage(canvas, layout, explored),
                                    angularClustersImage(canvas, layout),
                                    wallsImage(canvas, layout),
                                    extendedLinesImage(canvas, map, closed_doors, layout),
                                    cellsImage(canvas, layout),
                                    roomsImage(canvas, layout),
                                    startCellsImage(canvas, map, closed_doors, layout)};
  for (size_t k = 0; k < images.size(); ++k) writeImage(dir, layoutDebugImageNames()[k], images[k]);
}

}  // namespace hidden_rooms::prediction
